// The peer of bench_arap: CGAL's Surface_mesh_deformation (CGAL 5.5, its default Eigen sparse LDLT
// solver) on the same edits, with the same figures, so the two can be read side by side.
// Usage: bench_arap_cgal [resolution ...]                 (default: 100k 1M) prepare and time per iteration
//        bench_arap_cgal quality MESH SEL DEF              rigidity and self-intersections after 1..1000
//                                                          iterations, ORIGINAL_ARAP, SPOKES_AND_RIMS, SRE_ARAP
// The region maps as CGAL expects it: the free and handle vertices are the region of interest, the
// handle vertices its control vertices, the fixed vertices stay outside it.
#include <CGAL/Simple_cartesian.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/Surface_mesh_deformation.h>

#include <algorithm>
#include <cstdio>
#include <string>
#include <vector>

#include "bench/bench_common.h"
#include "msdeform/analysis/metrics.h"
#include "msdeform/analysis/self_intersections.h"
#include "msdeform/core/edit_case.h"
#include "msdeform/core/memory.h"
#include "msdeform/core/scenes.h"

using namespace msd::bench;

namespace {

using Kernel = CGAL::Simple_cartesian<double>;
using SurfaceMesh = CGAL::Surface_mesh<Kernel::Point_3>;
using VertexIndex = SurfaceMesh::Vertex_index;

SurfaceMesh to_cgal(const msd::Positions& P, const msd::Faces& F) {
  SurfaceMesh m;
  for (Eigen::Index v = 0; v < P.rows(); ++v) m.add_vertex(Kernel::Point_3(P(v, 0), P(v, 1), P(v, 2)));
  for (Eigen::Index f = 0; f < F.rows(); ++f)
    m.add_face(VertexIndex(F(f, 0)), VertexIndex(F(f, 1)), VertexIndex(F(f, 2)));
  return m;
}

msd::Positions positions(const SurfaceMesh& m) {
  msd::Positions X(m.number_of_vertices(), 3);
  for (VertexIndex v : m.vertices()) {
    const Kernel::Point_3& p = m.point(v);
    X.row(v.idx()) << p.x(), p.y(), p.z();
  }
  return X;
}

// One CGAL deformation of the edit: region of interest, control vertices and their targets set.
template <CGAL::Deformation_algorithm_tag Tag>
struct CgalArap {
  using Deformation = CGAL::Surface_mesh_deformation<SurfaceMesh, CGAL::Default, CGAL::Default, Tag>;
  SurfaceMesh mesh;
  Deformation deformation;
  double prepare_seconds = 0;

  explicit CgalArap(const msd::EditCase& c) : mesh(to_cgal(c.P, c.F)), deformation(mesh) {
    const auto t0 = Clock::now();
    for (Eigen::Index v = 0; v < c.P.rows(); ++v)
      if (!c.region.is_fixed(static_cast<int>(v))) deformation.insert_roi_vertex(VertexIndex(v));
    for (int v : c.region.constrained_vertices())
      if (c.region.handle_of(v) >= 0) deformation.insert_control_vertex(VertexIndex(v));
    if (!deformation.preprocess()) std::printf("CGAL: preprocess failed\n");
    prepare_seconds = seconds_since(t0);
    for (int v : c.region.constrained_vertices()) {
      const int k = c.region.handle_of(v);
      if (k < 0) continue;
      const msd::Vec3 t = msd::transform_point(c.transforms[k], c.P.row(v));
      deformation.set_target_position(VertexIndex(v), Kernel::Point_3(t.x(), t.y(), t.z()));
    }
  }
};

template <CGAL::Deformation_algorithm_tag Tag>
void quality_rows(const msd::EditCase& c, const char* name) {
  const msd::RigidityMetric rigidity(c.P, c.F);
  CgalArap<Tag> arap(c);
  int done = 0;
  for (int total : {1, 10, 100, 1000}) {
    arap.deformation.deform(total - done, 0.0);  // continues from the last iterate
    done = total;
    const msd::Positions out = positions(arap.mesh);
    const msd::RigidityError r = rigidity.measure(out);
    std::printf("%16s %10d %14.4f %14.4f %12d %14.2e\n", name, total, r.stats.mean, r.stats.p95,
                msd::count_self_intersections(out, c.F), msd::handle_error(c.P, out, c.region, c.transforms));
    std::fflush(stdout);
  }
}

template <CGAL::Deformation_algorithm_tag Tag>
void speed_row(const msd::EditCase& c, const char* name, int iterations) {
  CgalArap<Tag> arap(c);
  arap.deformation.deform(1, 0.0);  // the first call also finishes CGAL's lazy set-up
  // As bench_arap: the marginal cost of an iteration, (time of 2N iterations - time of N) / N.
  std::vector<double> frames;
  for (int f = 0; f < 5; ++f) {
    auto t0 = Clock::now();
    arap.deformation.deform(iterations, 0.0);
    const double once = ms_since(t0);
    t0 = Clock::now();
    arap.deformation.deform(2 * iterations, 0.0);
    frames.push_back((ms_since(t0) - once) / iterations);
  }
  std::sort(frames.begin(), frames.end());
  std::printf("%10ld %16s %11.2f %13.1f %13.1f\n", long(c.P.rows()), name, arap.prepare_seconds,
              frames[frames.size() / 2], frames.front());
  std::fflush(stdout);
}

}  // namespace

int main(int argc, char** argv) {
  msd::retain_freed_memory();
  if (argc >= 5 && std::string(argv[1]) == "quality") {
    const msd::EditCase c = msd::file_case(argv[2], argv[3], argv[4]);
    std::printf("%s: %ld vertices, %ld faces (CGAL %s)\n", argv[2], long(c.P.rows()), long(c.F.rows()),
                CGAL_VERSION_STR);
    std::printf("%16s %10s %14s %14s %12s %14s\n", "CGAL energy", "iterations", "rigidity mean", "rigidity p95",
                "self-isect", "handle error");
    quality_rows<CGAL::ORIGINAL_ARAP>(c, "ORIGINAL_ARAP");
    quality_rows<CGAL::SPOKES_AND_RIMS>(c, "SPOKES_AND_RIMS");
    quality_rows<CGAL::SRE_ARAP>(c, "SRE_ARAP");
    return 0;
  }
  const int iterations = 10;
  std::printf("%10s %16s %11s %13s %13s\n", "vertices", "CGAL energy", "prepare[s]", "iter med[ms]", "iter min[ms]");
  for (const auto& size : msd::bench::sizes(argc, argv, {"100k", "1M"})) {
    const msd::EditCase c = msd::scene_case("bend120", msd::parse_resolution(size));
    speed_row<CGAL::ORIGINAL_ARAP>(c, "ORIGINAL_ARAP", iterations);
    speed_row<CGAL::SPOKES_AND_RIMS>(c, "SPOKES_AND_RIMS", iterations);
  }
  return 0;
}
