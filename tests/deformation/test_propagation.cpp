#include <catch2/catch.hpp>

#include <cmath>

#include "msdeform/core/errors.h"
#include "msdeform/core/laplacian.h"
#include "msdeform/core/mesh_io.h"
#include "msdeform/core/scenes.h"
#include "msdeform/deformation/propagation.h"
#include "test_util.h"

using namespace msd;

namespace {

struct Case {
  std::string name;
  Mesh mesh;
  Positions P;
  Faces F;
  Region region;
};

Case lift_plane(int resolution = 5000, double bump_height = 0.05) {
  SceneOptions o;
  o.resolution = resolution;
  o.bump_height = bump_height;
  const Scene s = make_scene("lift", o);
  return {"lift plane", make_mesh(s.P, s.F), s.P, s.F, s.region};
}

Case knight() {
  Mesh m = load_mesh(test::shared_data("decimated-knight.off"));
  Region r = read_dmat_groups(test::shared_data("decimated-knight-selection.dmat"), static_cast<int>(m.n_vertices()));
  const Positions P = positions(m);
  const Faces F = faces(m);
  return {"knight", std::move(m), P, F, std::move(r)};
}

const char* field_name(PropagationField f) {
  switch (f) {
    case PropagationField::Euclidean: return "Euclidean";
    case PropagationField::Geodesic: return "Geodesic";
    case PropagationField::Harmonic: return "Harmonic";
  }
  return "?";
}

const PropagationField kFields[] = {PropagationField::Euclidean, PropagationField::Geodesic, PropagationField::Harmonic};
const PropagationBlend kBlends[] = {PropagationBlend::Matrix, PropagationBlend::Decomposed};

Mat4 affine(const Mat3& A, const Vec3& t) {
  Mat4 T = Mat4::Identity();
  T.topLeftCorner<3, 3>() = A;
  T.topRightCorner<3, 1>() = t;
  return T;
}

//! Rotation by angle about the line through `point` along `axis`.
Mat4 rotation_about(const Vec3& point, const Vec3& axis, double angle) {
  const Mat3 R = Eigen::AngleAxisd(angle, axis.normalized()).toRotationMatrix();
  return affine(R, point - R * point);
}

PropagationOptions options(PropagationField field, PropagationBlend blend = PropagationBlend::Matrix) {
  PropagationOptions o;
  o.field = field;
  o.blend = blend;
  return o;
}

Vec3 centroid(const Positions& P, const std::vector<int>& ids) {
  Vec3 c = Vec3::Zero();
  for (int v : ids) c += P.row(v).transpose();
  return c / ids.size();
}

}  // namespace

TEST_CASE("propagation fields are 1 on the handle, 0 on the fixed part and in [0,1] between", "[deformation][propagation]") {
  for (const Case& c : {lift_plane(), knight()}) {
    for (PropagationField field : kFields) {
      for (int k = 0; k < c.region.num_handles(); ++k) {
        INFO(c.name << ", " << field_name(field) << " field, handle " << k);
        const Eigen::VectorXd s = propagation_field(c.P, c.F, c.region, field, k);
        REQUIRE(s.size() == c.P.rows());
        int interior = 0;
        for (int i = 0; i < s.size(); ++i) {
          const int h = c.region.handle_of(i);
          if (h == k)
            REQUIRE(s[i] == 1.0);
          else if (c.region.is_fixed(i) || h >= 0)
            REQUIRE(s[i] == 0.0);
          else {
            REQUIRE(s[i] >= 0.0);
            REQUIRE(s[i] <= 1.0);
            interior += s[i] > 0.0 && s[i] < 1.0;
          }
        }
        // The field actually blends: most free vertices lie strictly between.
        CHECK(interior >= 0.9 * c.region.free_vertices().size());
      }
    }
  }
}

TEST_CASE("harmonic field satisfies the Laplace equation (9.2) at free vertices", "[deformation][propagation]") {
  for (const Case& c : {lift_plane(), knight()}) {
    INFO(c.name);
    const SparseMatrix W = cotan_laplacian(c.P, c.F).W;
    const double scale = W.diagonal().cwiseAbs().maxCoeff();
    for (int k = 0; k < c.region.num_handles(); ++k) {
      const Eigen::VectorXd s = propagation_field(c.P, c.F, c.region, PropagationField::Harmonic, k);
      const Eigen::VectorXd Ws = W * s;
      double residual = 0;
      for (int i : c.region.free_vertices()) residual = std::max(residual, std::abs(Ws[i]));
      INFO("handle " << k << ": max |W s| on free vertices " << residual << ", max |W_ii| " << scale);
      CHECK(residual <= 1e-9 * scale);
    }
  }
}

TEST_CASE("harmonic fields of several handles are a partition of the harmonic field of their union", "[deformation][propagation]") {
  // Linearity of (9.2): Σ_k s_k is harmonic with value 1 on every handle; with no fixed part (the knight's
  // selection has only handles) that is the constant 1.
  const Case c = knight();
  REQUIRE(c.region.num_handles() == 3);
  REQUIRE(c.region.fixed_vertices().empty());
  Eigen::VectorXd sum = Eigen::VectorXd::Zero(c.P.rows());
  for (int k = 0; k < 3; ++k) sum += propagation_field(c.P, c.F, c.region, PropagationField::Harmonic, k);
  CHECK((sum.array() - 1.0).abs().maxCoeff() <= 1e-9);
}

TEST_CASE("Euclidean field is (9.1) with exact nearest-vertex distances", "[deformation][propagation]") {
  for (const Case& c : {lift_plane(2000), knight()}) {
    const int nh = c.region.num_handles();
    for (int k = 0; k < nh; ++k) {
      INFO(c.name << " handle " << k);
      const Eigen::VectorXd s = propagation_field(c.P, c.F, c.region, PropagationField::Euclidean, k);
      double worst = 0;
      for (int i : c.region.free_vertices()) {
        double to_handle = INFINITY, to_zero = INFINITY;  // brute force over all vertices
        for (int j = 0; j < c.P.rows(); ++j) {
          const double d = (c.P.row(i) - c.P.row(j)).norm();
          const int h = c.region.handle_of(j);
          if (h == k) to_handle = std::min(to_handle, d);
          else if (h >= 0 || c.region.is_fixed(j)) to_zero = std::min(to_zero, d);
        }
        worst = std::max(worst, std::abs(s[i] - to_zero / (to_zero + to_handle)));
      }
      CHECK(worst <= 1e-14);
    }
  }
}

TEST_CASE("identity transforms return the input", "[deformation][propagation]") {
  for (const Case& c : {lift_plane(), knight()})
    for (PropagationField field : kFields)
      for (PropagationBlend blend : kBlends) {
        INFO(c.name << " " << field_name(field) << (blend == PropagationBlend::Matrix ? " Matrix" : " Decomposed"));
        PropagationOptions o;
        o.field = field;
        o.blend = blend;
        TransformationPropagation prop(o);
        prop.prepare(c.mesh, c.region);
        const Positions out = prop.deform(std::vector<Mat4>(c.region.num_handles(), Mat4::Identity()));
        CHECK((out - c.P).cwiseAbs().maxCoeff() <= 1e-12);
      }
}

TEST_CASE("handles move exactly by their transform, fixed vertices not at all", "[deformation][propagation]") {
  const Case plane = lift_plane();
  const Case kn = knight();
  // An affine transform with rotation, shear and translation per handle.
  const Mat3 shear = (Mat3() << 1.1, 0.2, 0, 0, 0.9, 0.1, 0, 0, 1.05).finished();
  for (const Case* c : {&plane, &kn})
    for (PropagationField field : kFields)
      for (PropagationBlend blend : kBlends) {
        INFO(c->name << " " << field_name(field) << (blend == PropagationBlend::Matrix ? " Matrix" : " Decomposed"));
        std::vector<Mat4> T;
        for (int k = 0; k < c->region.num_handles(); ++k)
          T.push_back(rotation_about(Vec3(0.1 * k, 0.2, 0.3), Vec3(1, 2, 3 - k), 0.4 + 0.3 * k) *
                      affine(shear, Vec3(0.05, -0.1 * k, 0.2)));
        PropagationOptions o;
        o.field = field;
        o.blend = blend;
        TransformationPropagation prop(o);
        prop.prepare(c->mesh, c->region);
        const Positions out = prop.deform(T);
        REQUIRE(out.allFinite());
        double handle_error = 0, fixed_error = 0;
        for (int i = 0; i < c->P.rows(); ++i) {
          const int k = c->region.handle_of(i);
          if (k >= 0) handle_error = std::max(handle_error, (out.row(i).transpose() - transform_point(T[k], c->P.row(i))).norm());
          if (c->region.is_fixed(i)) fixed_error = std::max(fixed_error, (out.row(i) - c->P.row(i)).norm());
        }
        CHECK(handle_error <= 1e-12);
        CHECK(fixed_error == 0.0);
        // Row weights never exceed 1 in sum (every vertex an affine blend of p and the T_k(p)).
        CHECK(prop.fields().rowwise().sum().maxCoeff() <= 1.0 + 1e-15);
      }
}

TEST_CASE("Matrix blending is the seed formula p' = s T(p) + (1 - s) p", "[deformation][propagation]") {
  const Case c = lift_plane();
  SceneOptions o;
  o.resolution = 5000;
  const Mat4 T = make_scene("bend120", o).transforms[0];
  TransformationPropagation prop;  // harmonic, Matrix
  prop.prepare(c.mesh, c.region);
  const Positions out = prop.deform({T});
  double worst = 0;
  for (int i = 0; i < c.P.rows(); ++i) {
    const double s = prop.fields()(i, 0);
    const Vec3 p = c.P.row(i);
    worst = std::max(worst, (out.row(i).transpose() - (s * transform_point(T, p) + (1 - s) * p)).norm());
  }
  CHECK(worst <= 1e-12);
}

TEST_CASE("Decomposed blending turns vertices about the handle centroid by s times the angle", "[deformation][propagation]") {
  const Case c = lift_plane();
  const Vec3 center = centroid(c.P, c.region.handle_vertices(0));
  const Vec3 axis = Vec3(0.3, -0.5, 1).normalized();
  const double theta = 2.5;  // large, so the chord shortcut of Matrix blending is obvious
  const Mat4 T = rotation_about(center, axis, theta);
  for (PropagationField field : kFields) {
    INFO(field_name(field));
    PropagationOptions o;
    o.field = field;
    o.blend = PropagationBlend::Decomposed;
    TransformationPropagation prop(o);
    prop.prepare(c.mesh, c.region);
    const Positions out = prop.deform({T});
    double worst = 0, radius_change = 0;
    for (int i = 0; i < c.P.rows(); ++i) {
      const double s = prop.fields()(i, 0);
      const Vec3 r = c.P.row(i).transpose() - center;
      const Vec3 expected = center + Eigen::AngleAxisd(s * theta, axis) * r;
      worst = std::max(worst, (out.row(i).transpose() - expected).norm());
      radius_change = std::max(radius_change, std::abs((out.row(i).transpose() - center).norm() - r.norm()));
    }
    CHECK(worst <= 1e-12);
    CHECK(radius_change <= 1e-12);  // every vertex keeps its distance to the handle centroid
  }
  // Matrix blending of the same rotation pulls half-way vertices towards the centre (chords).
  TransformationPropagation matrix;
  matrix.prepare(c.mesh, c.region);
  const Positions out = matrix.deform({T});
  double shrink = 0;
  for (int i = 0; i < c.P.rows(); ++i) {
    const double s = matrix.fields()(i, 0);
    if (s > 0.4 && s < 0.6) {
      const Vec3 r = c.P.row(i).transpose() - center;
      shrink = std::max(shrink, 1 - (out.row(i).transpose() - center).norm() / r.norm());
    }
  }
  CHECK(shrink > 0.1);
}

TEST_CASE("Decomposed blending interpolates translation, slerped rotation and stretch separately", "[deformation][propagation]") {
  const Case c = knight();  // three handles
  const int nh = c.region.num_handles();
  // A_k = R_k S_k with known polar factors (S_k symmetric positive definite): the decomposition is unique.
  std::vector<Mat4> T;
  std::vector<Mat3> rotations, stretches;
  for (int k = 0; k < nh; ++k) {
    const Mat3 R = Eigen::AngleAxisd(0.5 + 0.8 * k, Vec3(1, k, 2).normalized()).toRotationMatrix();
    Mat3 S;
    S << 1.2, 0.1 * k, 0.05, 0.1 * k, 0.8, 0.0, 0.05, 0.0, 1.0 + 0.1 * k;
    rotations.push_back(R);
    stretches.push_back(S);
    T.push_back(affine(R * S, Vec3(0.1, 0.2 * k, -0.3)));
  }
  PropagationOptions o;
  o.field = PropagationField::Geodesic;
  o.blend = PropagationBlend::Decomposed;
  TransformationPropagation prop(o);
  prop.prepare(c.mesh, c.region);
  const Positions out = prop.deform(T);
  double worst = 0;
  for (int i = 0; i < c.P.rows(); ++i) {
    const Vec3 p = c.P.row(i);
    Vec3 expected = p;
    for (int k = 0; k < nh; ++k) {
      const double s = prop.fields()(i, k);
      const Vec3 ck = centroid(c.P, c.region.handle_vertices(k));
      const Vec3 tau = transform_point(T[k], ck) - ck;
      const Eigen::Quaterniond q = Eigen::Quaterniond::Identity().slerp(s, Eigen::Quaterniond(rotations[k]));
      const Mat3 blend = q.toRotationMatrix() * (Mat3::Identity() + s * (stretches[k] - Mat3::Identity()));
      expected += s * tau + blend * (p - ck) - (p - ck);
    }
    worst = std::max(worst, (out.row(i).transpose() - expected).norm());
  }
  CHECK(worst <= 1e-12);

  // Pure translations: both blends agree.
  const std::vector<Mat4> moves = {affine(Mat3::Identity(), Vec3(0.1, 0, 0)), affine(Mat3::Identity(), Vec3(0, 0.2, 0)),
                                   affine(Mat3::Identity(), Vec3(0, 0, -0.3))};
  TransformationPropagation matrix(options(PropagationField::Geodesic));
  matrix.prepare(c.mesh, c.region);
  CHECK((matrix.deform(moves) - prop.deform(moves)).cwiseAbs().maxCoeff() <= 1e-14);
}

TEST_CASE("Decomposed blending of a reflection keeps det R = +1 and meets the handle exactly", "[deformation][propagation]") {
  const Case c = lift_plane(2000);
  const Mat4 T = affine(Eigen::Vector3d(1, 1, -1).asDiagonal(), Vec3(0, 0, 0.2));  // mirror in z, then lift
  TransformationPropagation prop(options(PropagationField::Harmonic, PropagationBlend::Decomposed));
  prop.prepare(c.mesh, c.region);
  const Positions out = prop.deform({T});
  REQUIRE(out.allFinite());
  for (int v : c.region.handle_vertices(0))
    REQUIRE((out.row(v).transpose() - transform_point(T, c.P.row(v))).norm() <= 1e-12);
}

TEST_CASE("transfer functions reshape the field on free vertices only", "[deformation][propagation]") {
  const Case c = lift_plane(2000);
  const Eigen::VectorXd raw = propagation_field(c.P, c.F, c.region, PropagationField::Harmonic);
  PropagationOptions smooth;
  smooth.transfer = PropagationTransfer::SmoothStep;
  TransformationPropagation a(smooth);
  a.prepare(c.mesh, c.region);
  PropagationOptions custom;
  custom.transfer = PropagationTransfer::Custom;
  custom.custom_transfer = [](double s) { return std::sqrt(s); };
  TransformationPropagation b(custom);
  b.prepare(c.mesh, c.region);
  for (int i = 0; i < c.P.rows(); ++i) {
    const double s = raw[i];
    REQUIRE(a.fields()(i, 0) == Approx(3 * s * s - 2 * s * s * s).margin(1e-15));
    REQUIRE(b.fields()(i, 0) == Approx(std::sqrt(s)).margin(1e-15));
  }

  PropagationOptions bad;
  bad.transfer = PropagationTransfer::Custom;
  bad.custom_transfer = [](double s) { return 2 * s; };
  TransformationPropagation c_bad(bad);
  CHECK_THROWS_AS(c_bad.prepare(c.mesh, c.region), InvalidInput);
  CHECK_FALSE(c_bad.prepared());

  PropagationOptions missing;
  missing.transfer = PropagationTransfer::Custom;
  CHECK_THROWS_AS(TransformationPropagation(missing), InvalidInput);
  PropagationOptions ignored;
  ignored.custom_transfer = [](double s) { return s; };
  CHECK_THROWS_AS(TransformationPropagation(ignored), InvalidInput);
}

TEST_CASE("one handle and no fixed part: the whole mesh moves rigidly", "[deformation][propagation]") {
  Case c = knight();
  std::vector<int> codes = c.region.codes();
  for (int& code : codes)
    if (code > Region::kFirstHandle) code = Region::kFree;  // keep handle 0 only
  c.region = Region::from_codes(codes);
  const Mat4 T = rotation_about(Vec3(0.1, 0, 0), Vec3(0, 1, 0), 1.0);
  for (PropagationField field : kFields) {
    INFO(field_name(field));
    CHECK((propagation_field(c.P, c.F, c.region, field).array() == 1.0).all());
    TransformationPropagation prop(options(field));
    prop.prepare(c.mesh, c.region);
    const Positions out = prop.deform({T});
    double worst = 0;
    for (int i = 0; i < c.P.rows(); ++i)
      worst = std::max(worst, (out.row(i).transpose() - transform_point(T, c.P.row(i))).norm());
    CHECK(worst <= 1e-12);
  }
}

TEST_CASE("propagation: misuse gives the Deformer's errors", "[deformation][propagation]") {
  const Case c = lift_plane(500);
  TransformationPropagation prop;
  CHECK(prop.name() == "propagate");
  CHECK_THROWS_AS(prop.deform({Mat4::Identity()}), UsageError);  // before prepare

  const Region no_handle(static_cast<int>(c.P.rows()), Region::kFixed);
  CHECK_THROWS_AS(prop.prepare(c.mesh, no_handle), InvalidInput);
  CHECK_THROWS_AS(propagation_field(c.P, c.F, c.region, PropagationField::Harmonic, 1), InvalidInput);
  CHECK_THROWS_AS(propagation_field(c.P, c.F, Region(3), PropagationField::Harmonic), InvalidInput);

  prop.prepare(c.mesh, c.region);
  CHECK(prop.fields().rows() == c.P.rows());
  CHECK(prop.fields().cols() == 1);
  CHECK_THROWS_AS(prop.deform({}), UsageError);
  CHECK_THROWS_AS(prop.deform({Mat4::Identity(), Mat4::Identity()}), UsageError);
  Mat4 projective = Mat4::Identity();
  projective(3, 0) = 0.5;
  CHECK_THROWS_AS(prop.deform({projective}), InvalidInput);
  Mat4 nan = Mat4::Identity();
  nan(0, 3) = NAN;
  CHECK_THROWS_AS(prop.deform({nan}), InvalidInput);

  PropagationOptions o;
  o.geodesic.time_factor = 0;
  CHECK_THROWS_AS(TransformationPropagation(o), InvalidInput);
  // The range the CLI allows (Python took 1e30, then failed in the factorisation advising a larger one).
  for (double m : {1e-7, 1e30, double(NAN)}) {
    o.geodesic.time_factor = m;
    CHECK_THROWS_WITH(TransformationPropagation(o), Catch::Matchers::Contains("must be in [1e-6, 1e6]"));
  }
  o.geodesic.time_factor = 1e6;
  CHECK_NOTHROW(TransformationPropagation(o));
}
