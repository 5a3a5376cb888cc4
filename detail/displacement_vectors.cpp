#include "msdeform/detail/displacement_vectors.h"

#include <algorithm>
#include <atomic>
#include <string>

#include "msdeform/core/errors.h"
#include "msdeform/core/mesh.h"
#include "msdeform/core/parallel.h"

namespace msd {
namespace {

// An edge whose tangential part is shorter than this fraction of its length is (nearly) parallel to the
// normal and gives no usable tangent direction.
constexpr double kMinTangentFraction = 1e-6;
// Faces with area below this fraction of their squared longest edge are zero-area (as in cotan_laplacian).
constexpr double kMinAreaFraction = 1e-14;
// A vertex normal sum shorter than this fraction of its terms' total length has cancelled: no direction.
constexpr double kMinNormalFraction = 1e-12;

}  // namespace

VertexFrames::VertexFrames(const Faces& F, int num_vertices) {
  for (Eigen::Index f = 0; f < F.rows(); ++f)
    for (int k = 0; k < 3; ++k)
      if (F(f, k) < 0 || F(f, k) >= num_vertices)
        throw InvalidInput("VertexFrames: face " + std::to_string(f) + " has vertex index " +
                           std::to_string(F(f, k)) + " out of range [0, " + std::to_string(num_vertices) +
                           ")");
  F_ = F;
  VertexFaces star = vertex_faces(F, num_vertices);
  face_offsets_ = std::move(star.offsets);
  incident_faces_ = std::move(star.faces);
  face_normals_.resize(F.rows(), 3);
  // Every corner lists its two neighbours in winding order; faces are visited in index order.
  std::vector<int> offsets(num_vertices + 1, 0);
  for (Eigen::Index f = 0; f < F.rows(); ++f)
    for (int k = 0; k < 3; ++k) offsets[F(f, k) + 1] += 2;
  for (int v = 0; v < num_vertices; ++v) offsets[v + 1] += offsets[v];
  std::vector<int> raw(offsets.back());
  std::vector<int> fill(offsets.begin(), offsets.end() - 1);
  for (Eigen::Index f = 0; f < F.rows(); ++f)
    for (int k = 0; k < 3; ++k) {
      const int v = F(f, k);
      raw[fill[v]++] = F(f, (k + 1) % 3);
      raw[fill[v]++] = F(f, (k + 2) % 3);
    }
  // Keep the first occurrence of each neighbour.
  offsets_.assign(num_vertices + 1, 0);
  neighbours_.clear();
  neighbours_.reserve(raw.size() / 2 + num_vertices);
  for (int v = 0; v < num_vertices; ++v) {
    const auto first = neighbours_.size();
    for (int i = offsets[v]; i < offsets[v + 1]; ++i)
      if (raw[i] != v &&
          std::find(neighbours_.begin() + first, neighbours_.end(), raw[i]) == neighbours_.end())
        neighbours_.push_back(raw[i]);
    offsets_[v + 1] = static_cast<int>(neighbours_.size());
  }
}

std::vector<int> VertexFrames::edge_order(int v) const {
  if (v < 0 || v >= num_vertices()) return {};
  return std::vector<int>(neighbours_.begin() + offsets_[v], neighbours_.begin() + offsets_[v + 1]);
}

void VertexFrames::compute(const Positions& P, Positions& N, Positions& T1, Positions& T2) const {
  const long nv = num_vertices();
  if (P.rows() != nv)
    throw UsageError("VertexFrames::compute: " + std::to_string(P.rows()) + " positions for " +
                     std::to_string(nv) + " vertices");
  if (N.rows() != nv) N.resize(nv, 3);
  if (T1.rows() != nv) T1.resize(nv, 3);
  if (T2.rows() != nv) T2.resize(nv, 3);
  parallel_for_chunks(F_.rows(), [&](long begin, long end) {
    for (long f = begin; f < end; ++f) {
      const Vec3 p0 = P.row(F_(f, 0)), p1 = P.row(F_(f, 1)), p2 = P.row(F_(f, 2));
      const Vec3 n = (p1 - p0).cross(p2 - p0);  // length 2 · area: area weighting
      const double longest2 =
          std::max({(p1 - p0).squaredNorm(), (p2 - p1).squaredNorm(), (p0 - p2).squaredNorm()});
      face_normals_.row(f) = n.norm() > kMinAreaFraction * 2 * longest2 ? n : Vec3::Zero();
    }
  });
  parallel_for_chunks(nv, [&](long begin, long end) {
    for (long v = begin; v < end; ++v) {
      Vec3 sum = Vec3::Zero();
      double weight = 0;
      for (int i = face_offsets_[v]; i < face_offsets_[v + 1]; ++i) {
        const Vec3 fn = face_normals_.row(incident_faces_[i]);
        sum += fn;
        weight += fn.norm();
      }
      const double len = sum.norm();
      if (!(len > kMinNormalFraction * weight) || !(len > 0)) {  // no normal: world frame
        N.row(v) = Vec3::UnitZ();
        T1.row(v) = Vec3::UnitX();
        T2.row(v) = Vec3::UnitY();
        continue;
      }
      const Vec3 n = sum / len;
      N.row(v) = n;
      const Vec3 p = P.row(v);
      Vec3 t = Vec3::Zero();
      bool found = false;
      for (int i = offsets_[v]; i < offsets_[v + 1] && !found; ++i) {
        const Vec3 e = Vec3(P.row(neighbours_[i])) - p;
        t = e - e.dot(n) * n;
        const double t_len = t.norm();
        if (t_len > kMinTangentFraction * e.norm() && t_len > 0) {
          t /= t_len;
          found = true;
        }
      }
      if (!found) {  // every edge (nearly) parallel to n: the world axis least aligned with n
        int axis = 0;
        n.cwiseAbs().minCoeff(&axis);
        const Vec3 e = Vec3::Unit(axis);
        t = (e - e.dot(n) * n).normalized();
      }
      T1.row(v) = t;
      T2.row(v) = n.cross(t);
    }
  });
}

DisplacementVectors::DisplacementVectors(const DisplacementVectorOptions& options) : options_(options) {}

void DisplacementVectors::encode(const Positions& S, const Faces& Fs, const Positions& B, const Faces& Fb) {
  const char* where = "DisplacementVectors::encode";
  if (S.rows() != B.rows())
    throw InvalidInput(std::string(where) + ": S has " + std::to_string(S.rows()) + " vertices, B has " +
                       std::to_string(B.rows()) +
                       "; displacement vectors need S and B with the same connectivity");
  if (Fs.rows() != Fb.rows())
    throw InvalidInput(std::string(where) + ": S has " + std::to_string(Fs.rows()) + " faces, B has " +
                       std::to_string(Fb.rows()) +
                       "; displacement vectors need S and B with the same connectivity");
  for (Eigen::Index f = 0; f < Fs.rows(); ++f)
    if (Fs.row(f) != Fb.row(f))
      throw InvalidInput(std::string(where) + ": face " + std::to_string(f) + " differs between S and B; " +
                         "displacement vectors need S and B with the same connectivity");
  check_finite(S, where, "S");
  check_finite(B, where, "B");
  encoded_ = false;
  frames_ = VertexFrames(Fb, static_cast<int>(B.rows()));
  const Positions H = S - B;
  if (options_.frame == DisplacementFrame::Global) {
    coefficients_ = H;
  } else {
    frames_.compute(B, N_, T1_, T2_);
    coefficients_.resize(H.rows(), 3);
    coefficients_.col(0) = (H.array() * N_.array()).rowwise().sum();  // (9.8): α = h · n
    coefficients_.col(1) = (H.array() * T1_.array()).rowwise().sum();
    coefficients_.col(2) = (H.array() * T2_.array()).rowwise().sum();
  }
  encoded_ = true;
}

void DisplacementVectors::reconstruct(const Positions& B_deformed, Positions& out) {
  if (!encoded_) throw UsageError("DisplacementVectors::reconstruct: called before encode()");
  const long nv = static_cast<long>(coefficients_.rows());
  if (B_deformed.rows() != nv)
    throw UsageError("DisplacementVectors::reconstruct: deformed base has " +
                     std::to_string(B_deformed.rows()) + " vertices, the encoded base had " +
                     std::to_string(nv));
  const bool local = options_.frame == DisplacementFrame::Local;
  if (local) frames_.compute(B_deformed, N_, T1_, T2_);
  if (out.rows() != nv) out.resize(nv, 3);
  std::atomic<bool> finite{true};
  parallel_for_chunks(nv, [&](long begin, long end) {
    bool chunk_finite = true;
    for (long v = begin; v < end; ++v) {
      const Vec3 c = coefficients_.row(v);
      Vec3 p = B_deformed.row(v);
      if (local)
        p += c[0] * Vec3(N_.row(v)) + c[1] * Vec3(T1_.row(v)) + c[2] * Vec3(T2_.row(v));  // (9.8) on B'
      else
        p += c;
      out.row(v) = p;
      chunk_finite = chunk_finite && p.allFinite();
    }
    if (!chunk_finite) finite = false;
  });
  if (!finite) {
    check_finite(B_deformed, "DisplacementVectors::reconstruct", "the deformed base");
    throw InvalidInput("DisplacementVectors::reconstruct: non-finite result from a finite base (overflow?)");
  }
}

}  // namespace msd
