#pragma once
//! \file Regions: which vertices are fixed, free to deform, or part of handle k; and handle transforms.

#include <cstdint>
#include <string>
#include <vector>

#include "msdeform/core/types.h"

namespace msd {

//! Per-vertex role in an edit. Stored as Botsch–Sorkine selection codes: 0 fixed, 1 free, 2 + k handle k.
class Region {
 public:
  static constexpr int kFixed = 0;
  static constexpr int kFree = 1;
  static constexpr int kFirstHandle = 2;

  Region() = default;
  //! num_vertices vertices, all with the same code (free by default).
  explicit Region(int num_vertices, int code = kFree);
  //! From selection codes (0 fixed, 1 free, 2+k handle k). \throw InvalidInput on a negative code.
  static Region from_codes(std::vector<int> codes);

  int num_vertices() const { return static_cast<int>(codes_.size()); }
  //! 1 + the largest handle index in use (0 when there is no handle).
  int num_handles() const { return num_handles_; }
  int code(int v) const { return codes_[v]; }
  const std::vector<int>& codes() const { return codes_; }
  bool is_fixed(int v) const { return codes_[v] == kFixed; }
  bool is_free(int v) const { return codes_[v] == kFree; }
  //! Both fixed, or both on one handle: the edit moves the edge (u, v) rigidly.
  bool placed_together(int u, int v) const { return codes_[u] == codes_[v] && codes_[u] != kFree; }
  //! Placed by different transforms (fixed and a handle, or two handles): nothing deforms between them, so
  //! the edit stretches or tears the edge (u, v).
  bool placed_apart(int u, int v) const {
    return codes_[u] != codes_[v] && codes_[u] != kFree && codes_[v] != kFree;
  }
  //! Handle index of v, or -1 if v is fixed or free.
  int handle_of(int v) const { return codes_[v] >= kFirstHandle ? codes_[v] - kFirstHandle : -1; }

  void set_fixed(const std::vector<int>& vertices) { set(vertices, kFixed); }
  void set_free(const std::vector<int>& vertices) { set(vertices, kFree); }
  void set_handle(const std::vector<int>& vertices, int handle) { set(vertices, kFirstHandle + handle); }

  //! Vertex indices with the given role, ascending.
  std::vector<int> free_vertices() const;
  std::vector<int> constrained_vertices() const;  //!< fixed and handle vertices
  std::vector<int> handle_vertices(int handle) const;
  std::vector<int> fixed_vertices() const;

  //! Checks the region against a shape of num_vertices points: same vertex count and every handle
  //! 0..num_handles()-1 non-empty. With faces (F #F by 3, a surface method), also that every connected
  //! component of free vertices touches a fixed or handle vertex through an edge of F (else its shape is
  //! undetermined and the systems are singular); space methods pass no faces.
  //! With faces, also that the fixed part and every handle hold a vertex of a face, of a face whose
  //! `usable` entry is nonzero when `usable` (#F flags) is given: surface methods leave degenerate faces
  //! out, so a fixed part or handle touching only those holds or moves nothing of the surface.
  //! \throw InvalidInput on a count mismatch or an empty handle; TopologyError naming the component, its
  //! size and one of its vertices, or the fixed part or handle and one of its vertices.
  void validate(int num_vertices, const Faces* F = nullptr, const std::vector<char>* usable = nullptr) const;

 private:
  void set(const std::vector<int>& vertices, int code);
  std::vector<int> codes_;
  int num_handles_ = 0;
};

//! Reads a Botsch–Sorkine .sel file: '#' comments, then one code per vertex (0 fixed, 1 free, 2 handle;
//! msdeform extends 2 + k to handle k). \throw InvalidInput with file and line on a wrong count, a code
//! that is not a non-negative integer, or a missing file.
Region read_sel(const std::string& path, int num_vertices);
//! Writes codes as a .sel file (atomically). \throw InvalidInput, before anything is written, for handle
//! codes that are not consecutive (a handle with no vertex below one that has some), which validate()
//! refuses.
void write_sel(const Region& region, const std::string& path);

//! Reads a libigl dense-matrix (.dmat) group file, one column of num_vertices integers: -1 free,
//! g >= 0 handle g. \throw InvalidInput on a wrong header, count or value.
Region read_dmat_groups(const std::string& path, int num_vertices);

//! Reads a .def file: one 4x4 affine matrix per handle, 16 numbers each, row by row (4 numbers per line, or
//! a whole matrix on one line); '#' comments. \throw InvalidInput if the count is not a multiple of 16, a
//! line holds another count (a row split over lines), a number is malformed or non-finite, or a last row
//! is not (0 0 0 1).
std::vector<Mat4> read_def(const std::string& path);
//! Writes transforms as a .def file (atomically). \throw InvalidInput for what read_def refuses (no
//! transforms, a non-finite entry, a last row other than 0 0 0 1), before anything is written.
void write_def(const std::vector<Mat4>& transforms, const std::string& path);

//! Vertices inside the axis-aligned box [lo, hi] (infinite corners allowed). \throw InvalidInput for a NaN
//! corner, or lo above hi in a coordinate (corners given the wrong way round).
std::vector<int> select_box(const Positions& P, const Vec3& lo, const Vec3& hi);
//! Vertices within radius of center. \throw InvalidInput for a negative or non-finite radius or centre.
std::vector<int> select_sphere(const Positions& P, const Vec3& center, double radius);
//! Vertices with (p - point) . normal >= 0. \throw InvalidInput for a zero or non-finite normal or point.
std::vector<int> select_halfspace(const Positions& P, const Vec3& point, const Vec3& normal);

//! Applies an affine 4x4 transform to a point.
inline Vec3 transform_point(const Mat4& T, const Vec3& p) { return T.topLeftCorner<3, 3>() * p + T.topRightCorner<3, 1>(); }

}  // namespace msd
