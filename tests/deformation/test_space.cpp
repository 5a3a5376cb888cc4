// Space deformations (seed 9.5.1 lattice FFD, 9.6 triharmonic RBF, and every space row of the catalogue
// on a Fig. 9.15-like input): affine precision, interpolation or the stated least-squares residual,
// control-point editing, and a soup of hundreds of inconsistently oriented components.

#include <random>

#include "msdeform/core/errors.h"
#include "msdeform/core/scenes.h"
#include "msdeform/deformation/lattice.h"
#include "msdeform/deformation/rbf.h"
#include "msdeform/reconstruction/catalogue.h"
#include "test_util.h"

namespace msd {
namespace {

// Every constrained vertex in one handle.
Region all_constrained_one_handle(const Region& region) {
  std::vector<int> codes = region.codes();
  for (int& c : codes)
    if (c != Region::kFree) c = Region::kFirstHandle;
  return Region::from_codes(codes);
}

std::vector<std::unique_ptr<SpaceDeformer>> space_methods() {
  std::vector<std::unique_ptr<SpaceDeformer>> out;
  for (const auto& entry : builtin_methods().entries()) {
    std::unique_ptr<Deformer> d = entry.make({}, builtin_methods());
    if (d->traits().domain != DeformerDomain::Space) continue;
    out.emplace_back(dynamic_cast<SpaceDeformer*>(d.release()));
    REQUIRE(out.back());
  }
  return out;
}

TEST_CASE("space methods: an affine motion of every constraint moves every point by it", "[space]") {
  const Scene& s = test::bent_bar();
  const double diag = bounding_box_diagonal(s.P);
  const Region one = all_constrained_one_handle(s.region);
  const Positions expected = test::transformed(test::general_affine(), s.P);
  for (auto& d : space_methods()) {
    INFO(d->name());
    d->prepare(s.P, s.F, one);
    CHECK(test::max_row_distance(d->deform({test::general_affine()}), expected) <= 1e-8 * diag);
    // The map is affine in space too: points far outside the shape follow it where the method defines
    // it everywhere (RBF; the lattice clamps outside its box).
    Positions probe(2, 3), mapped;
    probe << s.P.row(0) * 0.5 + s.P.row(s.P.rows() - 1) * 0.5, s.P.colwise().mean();
    d->evaluate(probe, mapped);
    CHECK(test::max_row_distance(mapped, test::transformed(test::general_affine(), probe)) <= 1e-8 * diag);
  }
}

TEST_CASE("lattice: the least-norm solve of (9.13) meets few constraints and states the residual of many",
          "[space][lattice]") {
  const Scene& s = test::bent_bar();
  const double diag = bounding_box_diagonal(s.P);
  LatticeDeformer lattice;
  lattice.prepare(s.P, s.F, s.region);
  REQUIRE(lattice.cells().maxCoeff() == 8);
  const Positions out = lattice.deform(s.transforms);
  const double measured = test::constraint_error(s.P, out, s.region, s.transforms);
  CHECK(lattice.frame_report().constraint_error == Approx(measured).margin(1e-12 * diag));
  CHECK(measured <= 2e-2 * diag);  // 120° bend with a 8-cell lattice: met in the least-squares sense
  // Three handle vertices and nothing fixed: under-determined, met to the regularisation's precision.
  Region few(static_cast<int>(s.P.rows()));
  std::vector<int> codes(s.P.rows(), Region::kFree);
  codes[0] = codes[s.P.rows() / 2] = codes[s.P.rows() - 1] = Region::kFirstHandle;
  lattice.prepare(s.P, s.F, Region::from_codes(codes));
  Mat4 T = Mat4::Identity();
  T.topLeftCorner<3, 3>() = Eigen::AngleAxisd(0.5, Vec3::UnitZ()).toRotationMatrix() * 1.3;
  T(1, 3) = 0.2;
  lattice.deform({T});
  CHECK(lattice.frame_report().constraint_error <= 1e-6 * diag);
}

TEST_CASE("lattice: without the affine part, control points no constraint sees stay at rest (seed 9.13)",
          "[space][lattice]") {
  const Scene& s = test::bent_bar();
  LatticeOptions o;
  o.least_norm.affine_part = false;
  LatticeDeformer lattice(o);
  std::vector<int> codes(s.P.rows(), Region::kFree);
  Eigen::Index axis = 0, top = 0, bottom = 0;  // the two ends of the bar's long axis
  (s.P.colwise().maxCoeff() - s.P.colwise().minCoeff()).maxCoeff(&axis);
  s.P.col(axis).maxCoeff(&top);
  s.P.col(axis).minCoeff(&bottom);
  codes[top] = Region::kFirstHandle;
  lattice.prepare(s.P, s.F, Region::from_codes(codes));
  Mat4 T = Mat4::Identity();
  T(0, 3) = 0.3;
  const Positions out = lattice.deform({T});
  CHECK((out.row(top) - s.P.row(top)).norm() == Approx(0.3).epsilon(1e-6));
  CHECK((out.row(bottom) - s.P.row(bottom)).norm() == 0.0);  // far from the only constraint: not moved
  // With the affine part (the default), the same edit translates everything.
  LatticeDeformer with_affine;
  with_affine.prepare(s.P, s.F, Region::from_codes(codes));
  CHECK((with_affine.deform({T}).row(bottom) - s.P.row(bottom)).norm() == Approx(0.3).epsilon(1e-9));
}

TEST_CASE("lattice: control-point editing, linear precision and clamping outside the box", "[space][lattice]") {
  const Scene& s = test::bent_bar();
  const double diag = bounding_box_diagonal(s.P);
  LatticeDeformer lattice;
  lattice.prepare(s.P, s.F, s.region);
  const Positions C = lattice.control_points();
  REQUIRE(C.rows() == lattice.num_coefficients());
  // Moving the control points by an affine map moves every point by it (the lattice reproduces
  // linear functions: Greville points).
  const Eigen::MatrixX3d moved = test::transformed(test::general_affine(), C) - C;
  Positions out;
  lattice.deform_controls(moved, out);
  CHECK(test::max_row_distance(out, test::transformed(test::general_affine(), s.P)) <= 1e-9 * diag);
  CHECK(lattice.frame_report().constraint_error == -1);
  // One control point moved: only points in its 4×4×4-cell support move.
  Eigen::MatrixX3d one = Eigen::MatrixX3d::Zero(C.rows(), 3);
  one(C.rows() / 2, 0) = 0.1;
  lattice.deform_controls(one, out);
  const Vec3 h = (C.row(1) - C.row(0)).transpose();  // x spacing (one cell)
  int moved_points = 0;
  for (Eigen::Index v = 0; v < s.P.rows(); ++v)
    if ((out.row(v) - s.P.row(v)).norm() > 0) {
      ++moved_points;
      CHECK(std::abs(s.P(v, 0) - C(C.rows() / 2, 0)) < 2 * h.x() + 1e-12);
    }
  CHECK(moved_points > 0);
  // Outside the lattice the parameters are clamped: finite and continuous.
  Positions far(2, 3), mapped;
  far << 100, 100, 100, 100.001, 100, 100;
  lattice.evaluate(far, mapped);
  CHECK(mapped.allFinite());
  CHECK((mapped.row(0) - mapped.row(1)).norm() == Approx(0.001).margin(1e-9));
  CHECK_THROWS_AS(lattice.deform_controls(Eigen::MatrixX3d::Zero(3, 3), out), UsageError);
  LatticeOptions partial;
  partial.cells = Eigen::Vector3i(2, 0, 2);  // some cell counts given, not all
  CHECK_THROWS_AS(LatticeDeformer(partial).prepare(s.P, s.F, s.region), InvalidInput);
}

TEST_CASE("lattice, rbf: sizes that would exhaust memory are refused when the method is made", "[space][errors]") {
  LatticeOptions lattice;
  lattice.cells_longest = 3000;
  CHECK_THROWS_AS(LatticeDeformer(lattice), InvalidInput);
  CHECK_THROWS_WITH(
      LatticeDeformer(lattice),
      Catch::Matchers::Contains("(cells_longest; Python: cells=N, --lattice-cells) must be in 1..64"));
  lattice.cells_longest = 64;
  CHECK_NOTHROW(LatticeDeformer(lattice));
  lattice.cells = {4, 1000, 4};
  CHECK_THROWS_AS(LatticeDeformer(lattice), InvalidInput);
  CHECK_THROWS_WITH(LatticeDeformer(lattice), Catch::Matchers::Contains("cell counts must be in 1..64"));
  lattice.cells = {4, 4, 4};
  lattice.margin = 1e9;
  CHECK_THROWS_AS(LatticeDeformer(lattice), InvalidInput);
  CHECK_THROWS_WITH(LatticeDeformer(lattice), Catch::Matchers::Contains("margin must be in 0..10"));
  RbfOptions rbf;
  rbf.max_centres = 1000000;
  CHECK_THROWS_AS(RbfDeformer(rbf), InvalidInput);
  CHECK_THROWS_WITH(RbfDeformer(rbf), Catch::Matchers::Contains("max_centres must be in 1..20000"));
}

TEST_CASE("rbf: interpolates every constraint and subsamples beyond max_centres", "[space][rbf]") {
  const Scene& s = test::bent_bar();
  const double diag = bounding_box_diagonal(s.P);
  RbfDeformer rbf;
  rbf.prepare(s.P, s.F, s.region);
  REQUIRE(rbf.centres().rows() == static_cast<Eigen::Index>(s.region.constrained_vertices().size()));
  Positions out = rbf.deform(s.transforms);
  CHECK(test::constraint_error(s.P, out, s.region, s.transforms) <= 1e-9 * diag);
  CHECK(rbf.frame_report().constraint_error <= 1e-9 * diag);
  CHECK_THROWS_AS(rbf.deform_controls(Eigen::MatrixX3d::Zero(1, 3), out), UsageError);  // no control points

  RbfOptions few;
  few.max_centres = 40;
  RbfDeformer sparse(few);
  sparse.prepare(s.P, s.F, s.region);
  CHECK(sparse.centres().rows() == 40);
  out = sparse.deform(s.transforms);
  const double measured = test::constraint_error(s.P, out, s.region, s.transforms);
  CHECK(sparse.frame_report().constraint_error == Approx(measured).margin(1e-12 * diag));
  CHECK(measured <= 0.05 * diag);  // 40 well-spread centres on two rings still hold them closely
  // Both groups (fixed and the handle) have centres.
  const std::vector<int> constrained = s.region.constrained_vertices();
  int on_handle = 0;
  for (int row : sparse.centre_constraints()) on_handle += s.region.handle_of(constrained[row]) == 0;
  CHECK(on_handle > 0);
  CHECK(on_handle < 40);
  CHECK_THROWS_AS(RbfDeformer(RbfOptions{0}), InvalidInput);
}

TEST_CASE("rbf: coplanar and duplicated constraints still give a solvable system", "[space][rbf]") {
  // A flat grid: constraints on two strips of one plane (the polynomial drops the normal direction),
  // with one constrained vertex duplicated (two vertices at one position).
  Positions P;
  Faces F;
  std::vector<bool> interior;
  test::jittered_grid(20, 0.0, P, F, interior);
  const double diag = bounding_box_diagonal(P);
  Positions Q(P.rows() + 1, 3);
  Q << P, P.row(0);
  std::vector<int> codes(Q.rows(), Region::kFree);
  for (Eigen::Index v = 0; v < P.rows(); ++v) {
    if (P(v, 0) < 0.1 * P.col(0).maxCoeff()) codes[v] = Region::kFixed;
    if (P(v, 0) > 0.9 * P.col(0).maxCoeff()) codes[v] = Region::kFirstHandle;
  }
  codes.back() = codes[0];
  RbfDeformer rbf;
  rbf.prepare(Q, Faces(0, 3), Region::from_codes(codes));
  Mat4 T = Mat4::Identity();
  T(2, 3) = 0.2;  // lift the handle strip out of the plane
  const Positions out = rbf.deform({T});
  CHECK(out.allFinite());
  CHECK(rbf.frame_report().constraint_error <= 1e-9 * diag);
  CHECK(out.row(0) == out.row(Q.rows() - 1));
}

// A Fig. 9.15-like input: `count` closed boxes, each its own component, on a long "car body" grid, with
// random faces wound the wrong way and some boxes sharing an edge with a neighbour (non-manifold
// edges once several boxes meet there).
struct Soup {
  Positions P;
  Faces F;
  std::vector<int> component;  // per vertex
};

Soup box_soup(int nx, int ny, int nz, unsigned seed) {
  Soup s;
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> coin(0, 1);
  const int boxes = nx * ny * nz;
  s.P.resize(8 * boxes, 3);
  s.F.resize(12 * boxes, 3);
  const int quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  int b = 0;
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i, ++b) {
        // Boxes of side 0.8 cell, every other one grown to touch its +x neighbour.
        const double grow = (i % 2 == 0) ? 1.0 : 0.8;
        for (int c = 0; c < 8; ++c) {
          const Vec3 corner((c & 1) ? grow : 0.0, (c & 2) ? 0.8 : 0.0, (c & 4) ? 0.8 : 0.0);
          s.P.row(8 * b + c) = (Vec3(i, j, k) + corner).transpose() * 0.1;
          s.component.push_back(b);
        }
        for (int q = 0; q < 6; ++q) {
          const int* v = quads[q];
          Eigen::RowVector3i t1(v[0], v[1], v[2]), t2(v[0], v[2], v[3]);
          if (coin(rng)) std::swap(t1[1], t1[2]);  // wound against its neighbours
          if (coin(rng)) std::swap(t2[1], t2[2]);
          s.F.row(12 * b + 2 * q) = t1.array() + 8 * b;
          s.F.row(12 * b + 2 * q + 1) = t2.array() + 8 * b;
        }
      }
  return s;
}

TEST_CASE("space methods: a soup of 360 inconsistently oriented boxes with three handles (Fig. 9.15)",
          "[space][soup]") {
  const Soup s = box_soup(20, 6, 3, 11);
  const int nv = static_cast<int>(s.P.rows());
  const double diag = bounding_box_diagonal(s.P);
  // Whole boxes are constrained (Fig. 9.15 moves whole parts): the rear (x < 0.4) is fixed, the "hood"
  // (x > 1.6) moves forward by 0.3, the front "wheel house" (bottom boxes at 1.3 < x < 1.5) by 0.2 and
  // the rear one (bottom boxes at 0.5 < x < 0.7) by 0.05, each rigidly; the boxes between stretch.
  std::vector<int> codes(nv, Region::kFree);
  for (int b = 0; b < nv / 8; ++b) {
    const Vec3 c = s.P.middleRows(8 * b, 8).colwise().mean().transpose();
    int code = Region::kFree;
    if (c.x() < 0.4) code = Region::kFixed;
    if (c.x() > 1.6) code = Region::kFirstHandle;
    if (c.z() < 0.1 && c.x() > 1.3 && c.x() < 1.5) code = Region::kFirstHandle + 1;
    if (c.z() < 0.1 && c.x() > 0.5 && c.x() < 0.7) code = Region::kFirstHandle + 2;
    std::fill(codes.begin() + 8 * b, codes.begin() + 8 * b + 8, code);
  }
  const Region region = Region::from_codes(codes);
  REQUIRE(region.num_handles() == 3);
  std::vector<Mat4> T(3, Mat4::Identity());
  T[0](0, 3) = 0.3;
  T[1](0, 3) = 0.2;
  T[2](0, 3) = 0.05;
  for (auto& d : space_methods()) {
    INFO(d->name());
    d->prepare(s.P, s.F, region);
    const Positions out = d->deform(T);
    REQUIRE(out.rows() == nv);
    REQUIRE(out.allFinite());
    // Every free box moved smoothly: its eight corners follow one affine map up to the second-order
    // term of a smooth map (below 15 % of the box side of 0.08 for this edit, whose constraints 0.1 apart
    // move by up to 0.15 relative to each other, 30 % for the cages' least-squares compromise: a torn or
    // crumpled box would be off by its whole size).
    double worst = 0;
    for (int b = 0; b < nv / 8; ++b) {
      if (codes[8 * b] != Region::kFree) continue;
      Eigen::Matrix<double, 8, 4> X;
      Eigen::Matrix<double, 8, 3> Y;
      for (int c = 0; c < 8; ++c) {
        X.row(c) << s.P.row(8 * b + c), 1.0;
        Y.row(c) = out.row(8 * b + c);
      }
      const Eigen::Matrix<double, 4, 3> A = X.colPivHouseholderQr().solve(Y);
      worst = std::max(worst, (X * A - Y).rowwise().norm().maxCoeff());
    }
    const bool cage = d->name().rfind("cage", 0) == 0;
    CHECK(worst <= (cage ? 0.3 : 0.15) * 0.08);
    // Components that touch stay touching: the map is one function of space, so corners at one
    // position (boxes grown to their +x neighbour) land at one position.
    double gap = 0;
    int touching = 0;
    for (int v = 0; v + 8 < nv; ++v)
      for (int w = 8 * (v / 8 + 1); w < 8 * (v / 8 + 2); ++w)
        if (s.P.row(v) == s.P.row(w)) {
          ++touching;
          gap = std::max(gap, (out.row(v) - out.row(w)).norm());
        }
    CHECK(touching > 100);
    CHECK(gap <= 1e-12);
    // The hood and the wheel houses keep their shape: moved by their translations, exactly (RBF) or to
    // the stated least-squares residual: a lattice of 8 cells cannot separate the wheel houses from
    // their neighbours (about 1.7 % of the diagonal), nor can the generated convex cage, whose vertices
    // all lie outside the body (about 2.4 %; a cage drawn around the parts would).
    const double error = test::constraint_error(s.P, out, region, T);
    CHECK(d->frame_report().constraint_error == Approx(error).margin(1e-12));
    CHECK(error <= (d->name() == "rbf" ? 1e-9 : cage ? 3e-2 : 2e-2) * diag);
  }
  // Surface methods refuse the soup with a named error instead of crashing.
  for (const std::string method : {"shell", "arap", "propagate"}) {
    INFO(method);
    std::unique_ptr<Deformer> d = builtin_methods().make(method);
    CHECK_THROWS_AS(d->prepare(s.P, s.F, region), Error);
  }
}

}  // namespace
}  // namespace msd

namespace msd {
namespace {

TEST_CASE("space methods: far from the origin, and a badly missed constraint is a warning", "[space]") {
  const Scene& s = test::bent_bar();
  const double diag = bounding_box_diagonal(s.P);
  // The same edit 1e8 away along (1, 1, 1): every method still works and meets its targets as closely
  // as at the origin, up to the coordinates' precision (1e8 · 2⁻⁵² ≈ 2e-8).
  const Vec3 offset = Vec3::Constant(1e8);
  Positions far = s.P.rowwise() + offset.transpose();
  std::vector<Mat4> T = s.transforms;
  for (Mat4& t : T) t.topRightCorner<3, 1>() += offset - t.topLeftCorner<3, 3>() * offset;
  for (auto& d : space_methods()) {
    INFO(d->name());
    d->prepare(s.P, s.F, s.region);
    d->deform(s.transforms);
    const double near_error = d->frame_report().constraint_error;
    d->prepare(far, s.F, s.region);
    const Positions out = d->deform(T);
    CHECK(out.allFinite());
    CHECK(d->frame_report().constraint_error <= near_error + 1e-6 * diag);
  }
  // Two centres cannot hold two rings: the frame says how far off it is and what to change.
  RbfDeformer two(RbfOptions{2});
  two.prepare(s.P, s.F, s.region);
  two.deform(s.transforms);
  REQUIRE(two.frame_report().constraint_error > 0.05 * diag);
  REQUIRE(two.frame_report().warnings.size() == 1);
  CHECK_THAT(two.frame_report().warnings[0], Catch::Matchers::Contains("--max-centres"));
}

}  // namespace
}  // namespace msd
