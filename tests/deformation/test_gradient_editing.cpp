#include <catch2/catch.hpp>

#include "msdeform/analysis/metrics.h"
#include "msdeform/core/laplacian.h"
#include "msdeform/core/scenes.h"
#include "msdeform/core/solver.h"
#include "deformation/edit_measures.h"
#include "msdeform/deformation/gradient_editing.h"
#include "msdeform/deformation/propagation.h"
#include "msdeform/deformation/shell.h"

using namespace msd;

namespace {
}  // namespace

TEST_CASE("gradient: identity frame is the rest shape and constraints are exact", "[deformation][gradient]") {
  const Scene s = test::small_scene("bend120");
  const double diag = bounding_box_diagonal(s.P);
  GradientEditing g;
  g.prepare(s.P, s.F, s.region);
  CHECK(test::max_row_distance(g.deform({Mat4::Identity()}), s.P) <= 1e-11 * diag);
  const Positions out = g.deform(s.transforms);
  CHECK(test::constraint_error(s.P, out, s.region, s.transforms) == 0.0);  // copied, not solved
  CHECK(out.allFinite());
}

TEST_CASE("gradient: the weights are propagation_field's harmonic fields and the frame solves (9.10)",
          "[deformation][gradient]") {
  const Scene s = test::small_scene("twist135");
  const double diag = bounding_box_diagonal(s.P);
  GradientEditing g;
  g.prepare(s.P, s.F, s.region);
  CHECK((g.weights().col(0) - propagation_field(s.P, s.F, s.region, PropagationField::Harmonic, 0))
            .cwiseAbs()
            .maxCoeff() <= 1e-12);
  const Positions out = g.deform(s.transforms);
  // The same minimiser from the operators of core/laplacian.h: Gᵀ A G p' = Gᵀ A J' with known rows.
  const SparseMatrix G = gradient_operator(s.P, s.F);
  const Eigen::VectorXd area = face_areas(s.P, s.F);
  Eigen::VectorXd a3(3 * s.F.rows());
  for (Eigen::Index f = 0; f < s.F.rows(); ++f) a3.segment<3>(3 * f).setConstant(area[f]);
  const SparseMatrix GtA = SparseMatrix(G.transpose()) * a3.asDiagonal();
  Eigen::MatrixXd target(3 * s.F.rows(), 3);  // rows 3f..3f+2: gradients (columns: x, y, z)
  double jacobian_error = 0;
  for (int f = 0; f < s.F.rows(); ++f) {
    target.middleRows<3>(3 * f) = g.target_jacobian(f).transpose();
    const Mat3 rest = (G.middleRows(3 * f, 3) * s.P).transpose();
    jacobian_error = std::max(jacobian_error, (rest - g.rest_jacobian(f)).cwiseAbs().maxCoeff());
  }
  CHECK(jacobian_error <= 1e-9);
  ConstrainedQuadratic poisson;
  const std::vector<int> known = s.region.constrained_vertices();
  poisson.prepare(GtA * G, known);
  Eigen::MatrixXd values(known.size(), 3);
  for (size_t c = 0; c < known.size(); ++c) values.row(c) = out.row(known[c]);
  const Eigen::MatrixXd linear = -(GtA * target);
  CHECK(test::max_row_distance(poisson.solve(values, &linear), out) <= 1e-8 * diag);
}

TEST_CASE("gradient: one rigid motion of several handles with weights summing to 1 moves the shape rigidly",
          "[deformation][gradient]") {
  const Scene s = test::small_scene("bar-bend120");
  std::vector<int> codes = s.region.codes();
  for (int& c : codes)
    if (c == Region::kFixed) c = Region::kFirstHandle + 1;  // the fixed ring becomes handle 1
  const Region two = Region::from_codes(codes);
  GradientEditing g;
  g.prepare(s.P, s.F, two);
  CHECK((g.weights().rowwise().sum().array() - 1).abs().maxCoeff() <= 1e-9);
  Mat4 T = Mat4::Identity();
  T.topLeftCorner<3, 3>() = Eigen::AngleAxisd(1.2, Vec3(1, -2, 0.5).normalized()).toRotationMatrix();
  T.topRightCorner<3, 1>() = Vec3(0.4, 0.1, -0.3);
  const Positions out = g.deform({T, T});
  CHECK(test::max_row_distance(out, test::rigid_motion(s.P, T.topLeftCorner<3, 3>(), T.topRightCorner<3, 1>())) <=
        1e-8 * bounding_box_diagonal(s.P));
}

TEST_CASE("gradient: a translated handle changes no gradient, so the free region is a membrane, not a smooth bend",
          "[deformation][gradient]") {
  // Seed 9.4.3 and 9.7: translation insensitivity. J' = J, so the result is the harmonic displacement
  // (shell with ks = 1, kb = 0), C⁰ at the region's boundary, against shell's C¹ bending.
  const Scene s = test::small_scene("lift");
  GradientEditing g;
  g.prepare(s.P, s.F, s.region);
  const Positions out = g.deform(s.transforms);
  for (int f = 0; f < s.F.rows(); f += 97) CHECK((g.target_jacobian(f) - g.rest_jacobian(f)).cwiseAbs().maxCoeff() <= 1e-12);
  ShellDeformer membrane(ShellOptions{1, 0}), bending(ShellOptions{0, 1});
  membrane.prepare(s.P, s.F, s.region);
  bending.prepare(s.P, s.F, s.region);
  const double diag = bounding_box_diagonal(s.P);
  CHECK(test::max_row_distance(out, membrane.deform(s.transforms)) <= 1e-8 * diag);
  const Positions smooth = bending.deform(s.transforms);
  const double crease_gradient = test::max_dihedral_change(s.P, out, s.F);
  const double crease_shell = test::max_dihedral_change(s.P, smooth, s.F);
  const double rigid_gradient = rigidity_error(s.P, out, s.F).stats.mean;
  const double rigid_shell = rigidity_error(s.P, smooth, s.F).stats.mean;
  WARN("lift: max dihedral change gradient " << crease_gradient << " shell " << crease_shell << "; rigidity mean gradient "
                                             << rigid_gradient << " shell " << rigid_shell);
  // Measured at 3k vertices: max dihedral change 0.505 (gradient) against 0.424 (shell, kb = 1).
  CHECK(crease_gradient > 1.1 * crease_shell);
}

TEST_CASE("gradient: on the survey bar twist and cylinder bend the rotation is followed, unlike shell",
          "[deformation][gradient][survey]") {
  for (const std::string name : {"bar", "cylinder"}) {
    const EditCase c = test::survey_case(name);
    GradientEditing g;
    ShellDeformer shell;
    g.prepare(c.P, c.F, c.region);
    shell.prepare(c.P, c.F, c.region);
    const Positions out = g.deform(c.transforms);
    const Positions ref = shell.deform(c.transforms);
    CHECK(test::constraint_error(c.P, out, c.region, c.transforms) <= 1e-12 * bounding_box_diagonal(c.P));
    const RigidityError eg = rigidity_error(c.P, out, c.F), es = rigidity_error(c.P, ref, c.F);
    const test::ScaleChange sg = test::local_scale_change(c.P, out, c.F, c.region);
    WARN(name << ": rigidity mean gradient " << eg.stats.mean << " max " << eg.stats.max << ", shell " << es.stats.mean
              << " max " << es.stats.max << "; scale change gradient max " << sg.max << " mean " << sg.mean);
    // Measured: bar twist 0.0093 against shell's 0.042, cylinder bend 0.043 against 0.108.
    CHECK(eg.stats.mean < 0.6 * es.stats.mean);
  }
}
