#include <catch2/catch.hpp>

#include <string>

#include "msdeform/core/adjacency.h"
#include "msdeform/core/edit_case.h"
#include "msdeform/core/errors.h"
#include "msdeform/core/laplacian.h"
#include "msdeform/core/scenes.h"
#include "msdeform/reconstruction/catalogue.h"
#include "test_util.h"

using namespace msd;
using Catch::Matchers::Contains;

TEST_CASE("a free vertex whose faces all have zero area: refused by name, or placed with its neighbours",
          "[deformation][solver]") {
  // A broken scan: one free vertex's one-ring collapsed onto it. Implicit Laplacian editing factored its
  // nearly singular system and moved the vertex 7.9 units under a 0.1 translation of CGAL's cow, exit 0.
  // The methods that see the vertex's zero area refuse it; ARAP and the multi-scale methods (whose shell
  // runs on the smoothed base) place it with its neighbours. (Before: 0.75 from them on this bend, where the
  // mean edge is 0.03.)
  SceneOptions options;
  options.resolution = 2000;
  Scene scene = make_scene("bend120", options);
  const double edge = mean_edge_length(scene.P, scene.F);
  const std::vector<int> free = scene.region.free_vertices();
  const int v = free[free.size() / 2];
  const VertexAdjacency rings = vertex_adjacency(scene.F, static_cast<int>(scene.P.rows()));
  for (const int* n = rings.begin(v); n != rings.end(v); ++n) scene.P.row(*n) = scene.P.row(v);
  for (const std::string& name : builtin_methods().names()) {
    const auto deformer = builtin_methods().make(name);
    if (deformer->traits().domain != DeformerDomain::Surface || name == "primo") continue;
    INFO(name);
    Positions out;
    try {
      deformer->prepare(scene.P, scene.F, scene.region);
      deformer->deform(scene.transforms, out);
    } catch (const Error& e) {
      CHECK_THAT(e.what(), Contains("vertex " + std::to_string(v)) && Contains("zero area"));
      continue;
    }
    Vec3 neighbours = Vec3::Zero();
    for (const int* n = rings.begin(v); n != rings.end(v); ++n) neighbours += out.row(*n).transpose();
    neighbours /= static_cast<double>(rings.end(v) - rings.begin(v));
    CHECK((out.row(v).transpose() - neighbours).norm() <= 3 * edge);
  }
}

namespace {
// The unit square as a 21 x 21 grid of vertices (index 21 i + j at (i, j) / 20) in 800 triangles: columns
// i < 3 fixed, i > 17 handle 0, the rest free.
struct Grid {
  static constexpr int n = 21;
  Positions P{n * n, 3};
  Faces F{2 * (n - 1) * (n - 1), 3};
  Region region;
  Grid() {
    std::vector<int> codes(P.rows(), Region::kFree);
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j) {
        P.row(i * n + j) = Vec3(i / double(n - 1), j / double(n - 1), 0);
        codes[i * n + j] = i < 3 ? Region::kFixed : i > 17 ? 2 : Region::kFree;
      }
    for (int i = 0, f = 0; i + 1 < n; ++i)
      for (int j = 0; j + 1 < n; ++j) {
        const int a = i * n + j;
        F.row(f++) = Eigen::RowVector3i(a, a + n, a + n + 1);
        F.row(f++) = Eigen::RowVector3i(a, a + n + 1, a + 1);
      }
    region = Region::from_codes(std::move(codes));
  }
};
}  // namespace

TEST_CASE("zero-area triangles that cut the surface in two are warned about by every surface method",
          "[deformation][solver]") {
  // A 21 x 21 grid whose column x = 0.5 lies on x = 0.55: its 40 triangles have no area, the cotan
  // Laplacian leaves them out, and shell moved the two sides as separate pieces (one at rest, one with
  // the handle: a cliff across the free region) without a word.
  Grid grid;
  for (int j = 0; j < Grid::n; ++j) grid.P(10 * Grid::n + j, 0) = 0.55;
  const Positions& P = grid.P;
  const Faces& F = grid.F;
  const Region& region = grid.region;
  for (const char* name : {"shell", "propagate", "gradient", "multiscale-normal"}) {
    INFO(name);
    const auto deformer = builtin_methods().make(name);
    deformer->prepare(P, F, region);
    int said = 0;
    for (const std::string& w : deformer->prepare_warnings())
      if (w.find(kZeroAreaCutWarning) != std::string::npos) {
        ++said;
        CHECK_THAT(w, Contains("40 zero-area triangle(s)") && Contains("2 pieces"));
      }
    CHECK(said == 1);
  }
}

TEST_CASE(
    "needle triangles that cut the surface, or clamped a thousandfold, are warned about by every surface "
    "method, naming a face",
    "[deformation][solver]") {
  // A 21 x 21 grid whose one-ring around the middle vertex lies on a line, with the vertex 1e-8 off it: the
  // ring's triangles are needles whose cotangents the cotan Laplacian clamps, and the shell left the vertex
  // 0.16 behind its neighbours under a 0.3 lift (exit 0, the only warning blaming large rotations). The
  // one-ring shrunk to 1e-12 of its size joins the rest through well-shaped triangles too, but its needles'
  // cotangents (2.5e12) are clamped to 1e5: explicit Laplacian editing left the cluster at rest.
  const Grid grid;
  const int c = 10 * Grid::n + 10;
  const Faces& F = grid.F;
  const VertexAdjacency rings = vertex_adjacency(F, static_cast<int>(grid.P.rows()));
  enum Variant { kGrid, kSquashed, kShrunk };
  for (const Variant variant : {kGrid, kSquashed, kShrunk}) {
    Positions Q = grid.P;
    for (const int* r = rings.begin(c); r != rings.end(c) && variant != kGrid; ++r)
      Q.row(*r) =
          variant == kSquashed ? Vec3(Q(*r, 0), Q(c, 1), 0) : Vec3(Q.row(c) + 1e-12 * (Q.row(*r) - Q.row(c)));
    if (variant == kSquashed) Q(c, 1) += 1e-8;
    for (const char* name :
         {"shell", "laplacian", "propagate", "gradient", "arap", "multiscale-normal", "euclidean"}) {
      INFO(name << " on variant " << variant);
      const bool euclidean = std::string(name) == "euclidean";
      MethodSettings settings;
      settings.laplacian.implicit = false;
      if (euclidean) settings.propagation.field = PropagationField::Euclidean;  // no Laplacian: no warning
      const auto deformer = builtin_methods().make(euclidean ? "propagate" : name, settings);
      try {
        deformer->prepare(Q, F, grid.region);
      } catch (const Error& e) {  // a method that cannot fit the ring says where
        CHECK(variant != kGrid);
        CHECK_THAT(e.what(), Contains("near vertex"));
        continue;
      }
      int said = 0;
      for (const std::string& w : deformer->prepare_warnings())
        if (w.find(kNeedleWarning) != std::string::npos) {
          ++said;
          CHECK_THAT(w, Contains("needle triangle(s) at free vertices (the first is face") &&
                            Contains(variant == kSquashed ? "join 2 pieces only through them"
                                                          : "cotangents up to 2.5e+12"));
        }
      CHECK(said == (variant == kGrid || euclidean ? 0 : 1));
    }
  }
}

TEST_CASE("a needle here and there is warned about mildly", "[deformation][solver][real]") {
  // CGAL's triceratops has 2 needles (cotangents up to 3e5) that cut nothing: the shell's result is sound,
  // and the warning does not say vertices may be left behind. A crack of 40 needles (cotangents 2.5e6)
  // across a grid cuts nothing either, yet implicit Laplacian editing lifted its rim 23 % above the handle
  // without a word.
  EditCase c = load_edit_case(test::cgal_mesh("triceratops.off"), "", "");
  std::vector<int> codes(static_cast<size_t>(c.P.rows()), Region::kFree);
  for (Eigen::Index v = 0; v < c.P.rows(); ++v)
    codes[v] = c.P(v, 0) < -5 ? Region::kFixed : c.P(v, 0) > 5 ? 2 : 1;
  const auto shell = builtin_methods().make("shell");
  shell->prepare(c.P, c.F, Region::from_codes(std::move(codes)));
  int said = 0;
  for (const std::string& w : shell->prepare_warnings())
    if (w.find(kNeedleWarning) != std::string::npos) {
      ++said;
      CHECK_THAT(w, Contains("2 needle triangle(s)") &&
                        Contains("the result may be distorted next to them") && !Contains("behind"));
    }
  CHECK(said == 1);
  Grid grid;
  for (int i = 6; i < 14; ++i) grid.P(i * Grid::n + 10, 1) = grid.P(i * Grid::n + 9, 1) + 1e-8;  // a crack
  const auto laplacian = builtin_methods().make("laplacian");
  laplacian->prepare(grid.P, grid.F, grid.region);
  said = 0;
  for (const std::string& w : laplacian->prepare_warnings())
    said += w.find(kNeedleWarning) != std::string::npos;
  CHECK(said == 1);
}

#ifdef MSD_HAVE_CHOLMOD
#include <cholmod.h>

namespace {
void* no_memory(size_t) { return nullptr; }
// CHOLMOD's allocations fail while it lives (restored also when a check throws).
struct CholmodOutOfMemory {
  void* (*saved)(size_t) = SuiteSparse_config.malloc_func;
  CholmodOutOfMemory() { SuiteSparse_config.malloc_func = &no_memory; }
  ~CholmodOutOfMemory() { SuiteSparse_config.malloc_func = saved; }
};
}  // namespace

TEST_CASE("a factorisation out of memory is reported as such by every method and never as a singular system",
          "[deformation][solver]") {
  SceneOptions options;
  options.resolution = 2000;
  const Scene scene = make_scene("lift", options);
  for (const std::string& name : builtin_methods().names()) {
    INFO(name);
    const auto deformer = builtin_methods().make(name);
    std::string message;
    {
      CholmodOutOfMemory fail;
      try {
        deformer->prepare(scene.P, scene.F, scene.region);
      } catch (const Error& e) {
        message = e.what();
      }
    }
    INFO(message);
    if (message.empty()) continue;  // a method without a sparse factorisation
    CHECK(message.find("out of memory") != std::string::npos);
    CHECK(message.find("singular") == std::string::npos);
  }
}
#endif
