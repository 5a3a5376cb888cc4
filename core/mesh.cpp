#include "core/mesh.h"

#include <cmath>
#include <string>

#include "core/errors.h"
#include "core/parallel.h"

namespace msd {

Positions positions(const Mesh& mesh) {
  Positions P(mesh.n_vertices(), 3);
  for (auto v : mesh.vertices()) {
    const auto& p = mesh.point(v);
    P.row(v.idx()) << p[0], p[1], p[2];
  }
  return P;
}

void set_positions(Mesh& mesh, const Positions& P) {
  if (P.rows() != static_cast<Eigen::Index>(mesh.n_vertices()))
    throw InvalidInput("set_positions: " + std::to_string(P.rows()) + " rows for a mesh of " +
                       std::to_string(mesh.n_vertices()) + " vertices");
  for (auto v : mesh.vertices()) mesh.set_point(v, Mesh::Point(P(v.idx(), 0), P(v.idx(), 1), P(v.idx(), 2)));
}

Faces faces(const Mesh& mesh) {
  Faces F(mesh.n_faces(), 3);
  for (auto f : mesh.faces()) {
    int k = 0;
    for (auto v : mesh.fv_range(f)) F(f.idx(), k++) = v.idx();
  }
  return F;
}

Mesh make_mesh(const Positions& P, const Faces& F) {
  Mesh mesh;
  mesh.reserve(P.rows(), P.rows() + F.rows(), F.rows());
  for (Eigen::Index i = 0; i < P.rows(); ++i) {
    if (!P.row(i).allFinite())
      throw InvalidInput("make_mesh: vertex " + std::to_string(i) + " has a non-finite coordinate");
    mesh.add_vertex(Mesh::Point(P(i, 0), P(i, 1), P(i, 2)));
  }
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    const int a = F(f, 0), b = F(f, 1), c = F(f, 2);
    for (int idx : {a, b, c})
      if (idx < 0 || idx >= P.rows())
        throw InvalidInput("make_mesh: face " + std::to_string(f) + " has vertex index " + std::to_string(idx) +
                           " out of range [0, " + std::to_string(P.rows()) + ")");
    if (a == b || b == c || a == c)
      throw InvalidInput("make_mesh: face " + std::to_string(f) + " repeats a vertex index");
    auto fh = mesh.add_face(mesh.vertex_handle(a), mesh.vertex_handle(b), mesh.vertex_handle(c));
    if (!fh.is_valid())
      throw InvalidInput("make_mesh: face " + std::to_string(f) + " (" + std::to_string(a) + ", " +
                         std::to_string(b) + ", " + std::to_string(c) +
                         ") makes an edge or vertex non-manifold or flips orientation");
  }
  return mesh;
}

VertexNormals::VertexNormals(const Faces& F, int num_vertices) : F_(F) {
  offsets_.assign(num_vertices + 1, 0);
  for (Eigen::Index f = 0; f < F.rows(); ++f)
    for (int k = 0; k < 3; ++k) ++offsets_[F(f, k) + 1];
  for (int v = 0; v < num_vertices; ++v) offsets_[v + 1] += offsets_[v];
  incident_.resize(offsets_.back());
  std::vector<int> fill(offsets_.begin(), offsets_.end() - 1);
  for (Eigen::Index f = 0; f < F.rows(); ++f)
    for (int k = 0; k < 3; ++k) incident_[fill[F(f, k)]++] = static_cast<int>(f);
  face_normals_.resize(F.rows(), 3);
}

void VertexNormals::compute(const Positions& P, Positions& N) const {
  const long nv = static_cast<long>(offsets_.size()) - 1;
  if (N.rows() != nv) N.resize(nv, 3);
  parallel_for_chunks(F_.rows(), [&](long b, long e) {
    for (long f = b; f < e; ++f) {
      const Vec3 p0 = P.row(F_(f, 0)), p1 = P.row(F_(f, 1)), p2 = P.row(F_(f, 2));
      face_normals_.row(f) = (p1 - p0).cross(p2 - p0);  // length = 2 * area: area weighting for free
    }
  });
  parallel_for_chunks(nv, [&](long b, long e) {
    for (long v = b; v < e; ++v) {
      Vec3 n = Vec3::Zero();
      for (int k = offsets_[v]; k < offsets_[v + 1]; ++k) n += face_normals_.row(incident_[k]);
      const double len = n.norm();
      N.row(v) = len > 0 ? Vec3(n / len) : Vec3::Zero();
    }
  });
}

Positions vertex_normals(const Positions& P, const Faces& F) {
  Positions N;
  VertexNormals(F, static_cast<int>(P.rows())).compute(P, N);
  return N;
}

double bounding_box_diagonal(const Positions& P) {
  if (P.rows() < 2) return 0.0;
  return (P.colwise().maxCoeff() - P.colwise().minCoeff()).norm();
}

}  // namespace msd
