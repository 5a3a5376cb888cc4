// One figure of the performance summary per process, so each case reports its own peak memory:
//   bench_summary bandwidth                   streamed GB/s (triad a = b + s·c, both cores, 3 × 512 MB)
//   bench_summary CASE SIZE                   CASE: factorisation, factorisation-libigl (the peer's solver on
//                                             the same matrix), shell, normal, vectors, transfer,
//                                             normal-subdivision (the control-mesh base)
// Prints one line "case size vertices prepare_s frame_ms frame_min_ms peak_MB bytes_per_vertex extra" that
// bench/run gathers into the table of the README's performance section. MSD_BENCH_FRAMES=N times N frames
// (default 31, transfer 11), e.g. to profile the frame alone. The scene is the bumpy plane's
// `lift` edit; the multi-scale cases use the low-pass base at detail scale 0.3 (bench_multiscale's setting).
#include <sys/resource.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/SparseCholesky>

#include "bench/bench_common.h"
#include "msdeform/core/errors.h"
#include "msdeform/core/laplacian.h"
#include "msdeform/core/memory.h"
#include "msdeform/core/parallel.h"
#include "msdeform/core/scenes.h"
#include "msdeform/core/solver.h"
#include "msdeform/deformation/shell.h"
#include "msdeform/reconstruction/multiscale.h"

using namespace msd::bench;

namespace {

double peak_megabytes() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return usage.ru_maxrss / 1024.0;  // kilobytes on Linux
}

void print(const char* name, const std::string& size, long vertices, double prepare, const std::vector<double>& frames,
           const std::string& extra) {
  const double peak = peak_megabytes();
  std::printf("%s %s %ld %.3f %.3f %.3f %.0f %.0f %s\n", name, size.c_str(), vertices, prepare,
              frames.empty() ? 0.0 : frames[frames.size() / 2], frames.empty() ? 0.0 : frames.front(), peak,
              peak * 1024 * 1024 / vertices, extra.empty() ? "-" : extra.c_str());
}

}  // namespace

int main(int argc, char** argv) {
  msd::retain_freed_memory();
  const std::string what = argc > 1 ? argv[1] : "";
  if (what == "bandwidth") {
    std::printf("bandwidth %.1f\n", triad_gigabytes_per_second());
    return 0;
  }
  if (argc != 3) {
    std::fprintf(stderr, "usage: bench_summary bandwidth | bench_summary factorisation|factorisation-libigl|shell|normal|vectors|transfer|normal-subdivision SIZE\n");
    return 2;
  }
  const std::string size = argv[2];
  msd::SceneOptions options;
  options.resolution = msd::parse_resolution(size);
  const msd::Scene scene = msd::make_scene("lift", options);
  const long nv = static_cast<long>(scene.P.rows());

  if (what == "factorisation" || what == "factorisation-libigl") {  // the shell's bi-Laplacian on the free vertices
    const msd::LaplaceOperator lap = msd::cotan_laplacian(scene.P, scene.F);
    const auto free = scene.region.free_vertices();
    const msd::SparseMatrix A = msd::submatrix(msd::polyharmonic_matrix(lap, 2), free, free);
    const auto t0 = Clock::now();
    if (what == "factorisation-libigl") {
      // The peer: libigl's min_quad_with_fixed factors a positive definite system with Eigen's
      // SimplicialLLT (AMD ordering). libigl is not packaged for Debian 12, so its solver runs here, from
      // Debian's Eigen, on the same matrix.
      const Eigen::SimplicialLLT<msd::SparseMatrix> llt(A);
      if (llt.info() != Eigen::Success) throw msd::SolverError("SimplicialLLT failed");
      const double seconds = seconds_since(t0);
      char extra[96];
      std::snprintf(extra, sizeof extra, "factor_nnz=%.3g", static_cast<double>(llt.matrixL().nestedExpression().nonZeros()));
      print("factorisation-libigl", size, nv, seconds, {}, extra);
      return 0;
    }
    msd::SparseSPDSolver solver;
    solver.factor(A);
    char extra[96];
    std::snprintf(extra, sizeof extra, "factor_nnz=%.3g", solver.factor_nonzeros());
    print("factorisation", size, nv, seconds_since(t0), {}, extra);
    return 0;
  }
  std::unique_ptr<msd::Deformer> deformer;
  if (what == "shell") {
    deformer = std::make_unique<msd::ShellDeformer>();
  } else if (what == "normal" || what == "vectors" || what == "transfer") {
    msd::MultiscaleOptions o;
    o.encoding.kind = msd::encoding_kind(what);
    o.decomposition.low_pass.detail_scale = 0.3;
    deformer = std::make_unique<msd::MultiscaleDeformer>(o);
  } else if (what == "normal-subdivision") {
    // The hierarchical base: the shell edits the plane's control mesh, a Loop stencil gives B' at full
    // resolution, normal displacements carry the details. No factorisation at full resolution.
    msd::MultiscaleOptions o;
    o.encoding.kind = msd::EncodingKind::Normal;
    o.decomposition.kind = msd::DecompositionKind::Subdivision;
    o.decomposition.control =
        std::make_shared<msd::ControlMesh>(msd::ControlMesh{scene.coarse_P, scene.coarse_F, scene.refinement});
    deformer = std::make_unique<msd::MultiscaleDeformer>(o);
  } else {
    std::fprintf(stderr, "bench_summary: unknown case '%s'\n", what.c_str());
    return 2;
  }
  const auto t0 = Clock::now();
  deformer->prepare(scene.P, scene.F, scene.region);
  const double prepare = seconds_since(t0);
  msd::Positions out(nv, 3);
  // MSD_BENCH_FRAMES sets the number of frames timed (more for a profile of the frame alone): a whole
  // number from 1 to 1000000, else refused.
  int num_frames = what == "transfer" ? 11 : 31;
  if (const char* text = std::getenv("MSD_BENCH_FRAMES")) {
    char* end = nullptr;
    const long n = std::strtol(text, &end, 10);
    if (end == text || *end != '\0' || n < 1 || n > 1000000) {
      std::fprintf(stderr, "bench_summary: MSD_BENCH_FRAMES='%s' is not a whole number from 1 to 1000000\n", text);
      return 2;
    }
    num_frames = static_cast<int>(n);
  }
  const auto frames = time_frames(num_frames, [&](int) { deformer->deform(scene.transforms, out); });
  print(what.c_str(), size, nv, prepare, frames, "");
  return 0;
}
