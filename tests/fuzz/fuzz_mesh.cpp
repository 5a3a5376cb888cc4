//! libFuzzer target for one mesh reader, chosen at compile time by MSD_FUZZ_EXTENSION (".off", ".obj",
//! ".ply", ".stl"). Beyond "no crash, no hang, no leak, no huge allocation" (libFuzzer and the
//! sanitizers), every input a reader accepts must satisfy what core/mesh_io.h promises:
//!   - load_soup: at least one vertex, finite coordinates, triangles whose corners are distinct, valid
//!     vertex ids, and no two triangles on the same vertex set;
//!   - saving the soup as OFF and loading it again gives the same vertices and triangles, bit for bit;
//!   - load_mesh keeps the file's vertices, in count, order and position, and its triangles (it may only
//!     turn some over), or refuses with InvalidInput or TopologyError.

#include <algorithm>
#include <array>
#include <set>

#include "fuzz_input.h"
#include "msdeform/core/mesh_io.h"

using namespace msd;

namespace {

void check_soup(const TriangleSoup& soup) {
  fuzz::check(soup.P.rows() > 0 && soup.P.cols() == 3, "a soup without vertices was returned");
  fuzz::check(soup.P.allFinite(), "a non-finite coordinate was returned");
  fuzz::check(soup.F.cols() == 3, "faces are not triangles");
  std::set<std::array<int, 3>> seen;
  for (Eigen::Index f = 0; f < soup.F.rows(); ++f) {
    std::array<int, 3> t{soup.F(f, 0), soup.F(f, 1), soup.F(f, 2)};
    for (int i : t) fuzz::check(i >= 0 && i < soup.P.rows(), "face " + std::to_string(f) + " has a bad vertex id");
    std::sort(t.begin(), t.end());
    fuzz::check(t[0] != t[1] && t[1] != t[2], "face " + std::to_string(f) + " repeats a vertex");
    fuzz::check(seen.insert(t).second, "face " + std::to_string(f) + " duplicates an earlier one");
  }
}

// The same triangle, possibly turned over: the same corners in either cyclic order.
bool same_triangle(const Faces& a, const Faces& b, Eigen::Index f) {
  std::array<int, 3> s{a(f, 0), a(f, 1), a(f, 2)}, t{b(f, 0), b(f, 1), b(f, 2)};
  std::sort(s.begin(), s.end());
  std::sort(t.begin(), t.end());
  return s == t;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = fuzz::write_input(data, size, MSD_FUZZ_EXTENSION);
  TriangleSoup soup;
  if (!fuzz::reads([&] { soup = load_soup(path); })) return 0;
  check_soup(soup);

  const std::string copy = fuzz::scratch_path(".off");
  save_mesh(soup.P, soup.F, copy);
  const TriangleSoup again = load_soup(copy);
  fuzz::check(again.P == soup.P && again.F == soup.F, "the soup saved as OFF does not load back the same");

  Mesh mesh;
  if (!fuzz::reads([&] { mesh = load_mesh(path); })) return 0;
  fuzz::check(static_cast<Eigen::Index>(mesh.n_vertices()) == soup.P.rows(), "load_mesh changed the vertex count");
  fuzz::check(positions(mesh) == soup.P, "load_mesh moved or reordered vertices");
  const Faces F = faces(mesh);
  fuzz::check(F.rows() == soup.F.rows(), "load_mesh changed the face count");
  for (Eigen::Index f = 0; f < F.rows(); ++f)
    fuzz::check(same_triangle(F, soup.F, f), "load_mesh changed face " + std::to_string(f));
  return 0;
}
