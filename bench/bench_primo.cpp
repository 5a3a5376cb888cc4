// PriMo (seed 9.8) on the bumpy plane bent by 120°: prepare time (edges, colouring, factorisation of the
// face Laplacian), then one frame from rest to the default tolerance (iterations, time per iteration).
// Usage: bench_primo [resolution ...]                    (default: 100k 1M)
//        bench_primo quality MESH SEL DEF [THICKNESS ...]  one frame from rest per thickness (default 0.5):
//                                                         iterations, time, rigidity mean/p95 (analysis
//                                                         RigidityMetric), handle error, self-intersecting
//                                                         face pairs
//        bench_primo survey SURVEY_DIR [CGAL_DIR [THICKNESS]]  the same on the survey edits (plane,
//                                                         cylinder, bar, cactus) and CGAL's cactus
//
// Measured (Release, 2 shared cores, default options: thickness 2, tolerance 1e-6, one frame from rest):
//   edit            vertices  iters  frame[s]  iter[s]  rigidity mean / p95  self-isect pairs
//   CGAL cactus          620     17      0.37     0.02   0.0202 / 0.1121      0   (thickness 0.5: 0.0288, 89 pairs)
//   survey plane       40401     17     124.5     7.3    0.00005 / 0.00017    0
//   survey cylinder     4802     79      24.4     0.31   0.0035 / 0.0170      0
//   survey bar          6084    105      48.4     0.46   0.0048 / 0.0152    206   (ARAP: 0.0035, 520 pairs)
//   survey cactus       5261     32      12.3     0.38   0.0016 / 0.0085      0
//   bend120 100k      103041   3 iterations in 133 s: ~44 s per iteration (one sparse Cholesky of ~7.4e5
//                              unknowns each), so a converged frame at 100k takes many minutes.
#include <cstdio>
#include <string>
#include <vector>

#include "bench/bench_common.h"
#include "msdeform/analysis/metrics.h"
#include "msdeform/analysis/self_intersections.h"
#include "msdeform/core/edit_case.h"
#include "msdeform/core/memory.h"
#include "msdeform/core/scenes.h"
#include "msdeform/deformation/primo.h"

using namespace msd::bench;

namespace {

double thickness = msd::PrimoOptions{}.thickness;

void header() {
  std::printf("%-14s %8s %9s %10s %6s %9s %10s %10s %9s %9s %9s %10s %6s\n", "edit", "vertices", "thickness",
              "prepare[ms]", "iters", "converged", "residual", "frame[ms]", "iter[ms]", "rig.mean", "rig.p95",
              "handle err", "pairs");
}

void quality(const std::string& name, const msd::EditCase& c) {
  msd::PrimoOptions o;
  o.thickness = thickness;
  msd::PrimoDeformer d(o);
  auto t0 = Clock::now();
  d.prepare(c.P, c.F, c.region);
  const double prepare = ms_since(t0);
  t0 = Clock::now();
  const msd::Positions out = d.deform(c.transforms);
  const double frame = ms_since(t0);
  const msd::FrameReport& r = d.frame_report();
  const msd::RigidityError rigidity = msd::RigidityMetric(c.P, c.F).measure(out);
  const double handle = msd::handle_error(c.P, out, c.region, c.transforms);
  const int pairs = msd::count_self_intersections(out, c.F);
  std::printf("%-14s %8ld %9.3g %10.1f %6d %9s %10.2e %10.1f %9.2f %9.5f %9.5f %10.2e %6d\n", name.c_str(),
              long(c.P.rows()), thickness, prepare, r.iterations, r.converged ? "yes" : "no", r.residual, frame,
              frame / std::max(1, r.iterations), rigidity.stats.mean, rigidity.stats.p95, handle, pairs);
  std::fflush(stdout);
}

}  // namespace

int main(int argc, char** argv) {
  msd::retain_freed_memory();
  if (argc >= 5 && std::string(argv[1]) == "quality") {
    const msd::EditCase c = msd::file_case(argv[2], argv[3], argv[4]);
    header();
    std::vector<double> thicknesses;
    for (int i = 5; i < argc; ++i) thicknesses.push_back(std::stod(argv[i]));
    if (thicknesses.empty()) thicknesses.push_back(thickness);
    for (double t : thicknesses) {
      thickness = t;
      quality(argv[2], c);
    }
    return 0;
  }
  if (argc >= 3 && std::string(argv[1]) == "survey") {
    const std::string dir = argv[2];
    if (argc >= 5) thickness = std::stod(argv[4]);
    header();
    for (const char* name : {"plane", "cylinder", "bar", "cactus"})
      quality(name, msd::file_case(dir + "/" + name + ".off", dir + "/" + name + ".sel", dir + "/" + name + ".def"));
    if (argc >= 4) {
      const std::string cgal = argv[3];
      quality("cgal-cactus", msd::file_case(cgal + "/data/meshes/cactus.off",
                                            cgal + "/examples/Surface_mesh_deformation/data/cactus.sel",
                                            cgal + "/examples/Surface_mesh_deformation/data/cactus.def"));
    }
    return 0;
  }
  const std::vector<std::string> sizes = msd::bench::sizes(argc, argv, {"100k", "1M"});
  std::printf("%10s %12s %8s %12s %12s %14s %14s\n", "vertices", "prepare[s]", "iters", "frame[s]", "iter[ms]",
              "warm iters", "warm frame[s]");
  for (const auto& size : sizes) {
    msd::SceneOptions options;
    options.resolution = msd::parse_resolution(size);
    const msd::Scene scene = msd::make_scene("bend120", options);
    msd::PrimoDeformer primo;
    auto t0 = Clock::now();
    primo.prepare(scene.P, scene.F, scene.region);
    const double prepare = seconds_since(t0);
    msd::Positions out(scene.P.rows(), 3);
    t0 = Clock::now();
    primo.deform(scene.transforms, out);
    const double frame = seconds_since(t0);
    const int iterations = primo.frame_report().iterations;
    // A warm-started frame: the handle moved on by 2° from the converged pose.
    std::vector<msd::Mat4> T = scene.transforms;
    msd::Mat4 step = msd::Mat4::Identity();
    step.topLeftCorner<3, 3>() = Eigen::AngleAxisd(2 * M_PI / 180, msd::Vec3::UnitY()).toRotationMatrix();
    T[0] = T[0] * step;
    t0 = Clock::now();
    primo.deform(T, out);
    const double warm = seconds_since(t0);
    std::printf("%10ld %12.2f %8d %12.2f %12.2f %14d %14.2f\n", long(scene.P.rows()), prepare, iterations, frame,
                1000 * frame / std::max(1, iterations), primo.frame_report().iterations, warm);
    std::fflush(stdout);
  }
  return 0;
}
