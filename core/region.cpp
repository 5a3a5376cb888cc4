#include "msdeform/core/region.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <sstream>

#include "msdeform/core/adjacency.h"
#include "msdeform/core/atomic_file.h"
#include "msdeform/core/errors.h"
#include "msdeform/core/extent.h"

namespace msd {

Region::Region(int num_vertices, int code) : codes_(num_vertices, code) {
  if (code < 0) throw InvalidInput("Region: negative selection code " + std::to_string(code));
  num_handles_ = code >= kFirstHandle && num_vertices > 0 ? code - kFirstHandle + 1 : 0;
}

Region Region::from_codes(std::vector<int> codes) {
  Region r;
  // Handle codes are consecutive and every handle has a vertex, so #V vertices have at most #V handles:
  // a larger code is refused before anything is sized by it.
  const long max_code = kFirstHandle + static_cast<long>(codes.size()) - 1;
  for (size_t v = 0; v < codes.size(); ++v)
    if (codes[v] < 0 || codes[v] > max_code)
      throw InvalidInput(
          "Region: vertex " + std::to_string(v) + " has selection code " + std::to_string(codes[v]) +
          " (0 fixed, 1 free, 2+k handle k; handle codes are consecutive, so " +
          std::to_string(codes.size()) + " vertices carry codes up to " + std::to_string(max_code) + ")");
  r.codes_ = std::move(codes);
  for (int c : r.codes_) r.num_handles_ = std::max(r.num_handles_, c - kFirstHandle + 1);
  return r;
}

void Region::set(const std::vector<int>& vertices, int code) {
  for (int v : vertices) {
    if (v < 0 || v >= num_vertices())
      throw InvalidInput("Region: vertex " + std::to_string(v) + " out of range [0, " + std::to_string(num_vertices()) + ")");
    codes_[v] = code;
  }
  num_handles_ = 0;
  for (int c : codes_) num_handles_ = std::max(num_handles_, c - kFirstHandle + 1);
}

namespace {
template <class Pred>
std::vector<int> vertices_where(const std::vector<int>& codes, Pred pred) {
  std::vector<int> out;
  for (int v = 0; v < static_cast<int>(codes.size()); ++v)
    if (pred(codes[v])) out.push_back(v);
  return out;
}
}  // namespace

std::vector<int> Region::free_vertices() const { return vertices_where(codes_, [](int c) { return c == kFree; }); }
std::vector<int> Region::constrained_vertices() const {
  return vertices_where(codes_, [](int c) { return c != kFree; });
}
std::vector<int> Region::fixed_vertices() const { return vertices_where(codes_, [](int c) { return c == kFixed; }); }
std::vector<int> Region::handle_vertices(int handle) const {
  return vertices_where(codes_, [&](int c) { return c == kFirstHandle + handle; });
}

void Region::validate(int num_vertices, const Faces* F, const std::vector<char>* usable) const {
  if (this->num_vertices() != num_vertices)
    throw InvalidInput("region has " + std::to_string(this->num_vertices()) + " vertex labels but the mesh has " +
                       std::to_string(num_vertices) + " vertices");
  std::vector<int> count(num_handles_, 0);
  for (int c : codes_)
    if (c >= kFirstHandle) ++count[c - kFirstHandle];
  for (int h = 0; h < num_handles_; ++h)
    if (count[h] == 0)
      throw InvalidInput("region: handle " + std::to_string(h) + " (selection code " + std::to_string(h + kFirstHandle) +
                         ") has no vertex, but handle " + std::to_string(num_handles_ - 1) +
                         " exists; handle codes must be consecutive");
  if (!F) return;
  const VertexAdjacency adjacency = vertex_adjacency(*F, num_vertices);
  // A handle, or a fixed part, of vertices that no (usable) face uses moves or holds nothing of the surface
  // (a handle left the surface at rest with handle error 0; a fixed part let the whole surface translate;
  // likewise through zero-area faces only). Group g: the fixed part (0), handle g − 1 (code g + 1).
  std::vector<char> on_face(num_vertices, 0);
  for (Eigen::Index f = 0; f < F->rows(); ++f)
    if (!usable || (*usable)[f])
      for (int k = 0; k < 3; ++k) on_face[(*F)(f, k)] = 1;
  std::vector<int> example(num_handles_ + 1, -1);
  std::vector<char> on_surface(num_handles_ + 1, 0);
  for (int v = 0; v < num_vertices; ++v) {
    if (codes_[v] == kFree) continue;
    const int g = codes_[v] == kFixed ? 0 : codes_[v] - kFirstHandle + 1;
    if (example[g] < 0) example[g] = v;
    on_surface[g] |= on_face[v];
  }
  for (int g = 0; g <= num_handles_; ++g)
    if (example[g] >= 0 && !on_surface[g])
      throw TopologyError(
          "region: " +
          (g == 0 ? std::string("the fixed part (selection code 0)")
                  : "handle " + std::to_string(g - 1) + " (selection code " +
                        std::to_string(g - 1 + kFirstHandle) + ")") +
          " holds only vertices that no face " + (usable ? "of nonzero area " : "") + "uses (e.g. vertex " +
          std::to_string(example[g]) + "), so it cannot " + (g == 0 ? "hold" : "move") +
          " the surface; select vertices of the surface, or use a space method (lattice, cage, rbf), which "
          "deforms the space around it");
  // Flood-fill the free vertices; each component must reach a constrained neighbour.
  std::vector<int> component(num_vertices, -1), stack;
  int num_components = 0;
  for (int seed = 0; seed < num_vertices; ++seed) {
    if (!is_free(seed) || component[seed] >= 0) continue;
    const int id = num_components++;
    bool anchored = false;
    int size = 0;
    stack.assign(1, seed);
    component[seed] = id;
    while (!stack.empty()) {
      const int v = stack.back();
      stack.pop_back();
      ++size;
      for (const int* w = adjacency.begin(v); w != adjacency.end(v); ++w) {
        if (!is_free(*w)) {
          anchored = true;
        } else if (component[*w] < 0) {
          component[*w] = id;
          stack.push_back(*w);
        }
      }
    }
    if (!anchored && size == 1 && adjacency.begin(seed) == adjacency.end(seed))
      throw TopologyError("region: free vertex " + std::to_string(seed) +
                          " is used by no face, so nothing determines where it goes; fix it or select it as part "
                          "of a handle, or remove it from the file");
    if (!anchored)
      throw TopologyError("region: free component " + std::to_string(id) + " (" + std::to_string(size) +
                          " vertices, e.g. vertex " + std::to_string(seed) +
                          ") touches no fixed or handle vertex, so its deformation is undetermined; "
                          "fix or select a vertex in it");
  }
}

namespace {

// Whitespace-separated numbers of a text file with '#' comments, each with its line number. More than
// at_most numbers (what the file should hold: expected) is an error at the first one too many, so a huge
// file costs no more than a right one. one_per_line (a file with one number per line, like a .sel): the
// errors about the count name the first line holding more than one, which explains them (the count alone
// blamed the file's last line); such a line is read as it is.
// Why a count is off, when a line of a file with one number per line holds more (0: none does).
std::string shared(int line) {
  return line > 0 ? "; line " + std::to_string(line) + " holds more than one (one per line is expected)" : "";
}

template <class T>
std::vector<std::pair<T, int>> read_numbers(const std::string& path, const char* who, const char* what,
                                            size_t at_most = SIZE_MAX, const std::string& expected = "",
                                            bool one_per_line = false) {
  const FileText file(path, who);
  const std::string_view text = file.text();
  std::vector<std::pair<T, int>> out;
  int line = 1, shared_line = 0;
  size_t i = 0;
  while (i < text.size()) {
    const char c = text[i];
    if (c == '\n' || (c == '\r' && text.substr(i + 1, 1) != "\n")) {  // LF, or a CR alone (CR LF counts once)
      ++line, ++i;
    } else if (c == '#') {
      while (i < text.size() && text[i] != '\n' && text[i] != '\r') ++i;
    } else if (std::isspace(static_cast<unsigned char>(c))) {
      ++i;
    } else {
      size_t e = i;
      while (e < text.size() && e - i < kMaxNumberLength && !std::isspace(static_cast<unsigned char>(text[e])) &&
             text[e] != '#')
        ++e;
      T value{};
      const char* first = text.data() + i + (text[i] == '+' ? 1 : 0);
      auto [ptr, ec] = std::from_chars(first, text.data() + e, value);
      if (ec != std::errc() || ptr != text.data() + e)
        throw InvalidInput(std::string(who) + ": " + path + " line " + std::to_string(line) + ": expected " + what +
                           ", found '" + printable(text.substr(i, std::min<size_t>(e - i, 40))) + "'");
      if (one_per_line && shared_line == 0 && !out.empty() && out.back().second == line) shared_line = line;
      if (out.size() == at_most)
        throw InvalidInput(std::string(who) + ": " + path + " line " + std::to_string(line) + ": more than " +
                           std::to_string(at_most) + " values (expected " + expected + ")" +
                           shared(shared_line));
      out.emplace_back(value, line);
      i = e;
    }
  }
  return out;
}

}  // namespace

Region read_sel(const std::string& path, int num_vertices) {
  const auto values = read_numbers<long>(
      path, "read_sel", "an integer selection code (0 fixed, 1 free, 2+ handle)", std::max(num_vertices, 0),
      "one label per vertex of the " + std::to_string(num_vertices) + "-vertex mesh",
      /*one_per_line=*/true);
  if (static_cast<int>(values.size()) != num_vertices) {
    int line = 0;  // the first line with two labels, if any
    for (size_t v = 1; v < values.size() && line == 0; ++v)
      if (values[v].second == values[v - 1].second) line = values[v].second;
    throw InvalidInput("read_sel: " + path + " has " + std::to_string(values.size()) +
                       " labels but the mesh has " + std::to_string(num_vertices) + " vertices" +
                       shared(line));
  }
  std::vector<int> codes(values.size());
  for (size_t v = 0; v < values.size(); ++v) {
    if (values[v].first < 0 || values[v].first > Region::kFirstHandle + static_cast<long>(values.size()) - 1)
      throw InvalidInput("read_sel: " + path + " line " + std::to_string(values[v].second) + ": label " +
                         std::to_string(values[v].first) + " for vertex " + std::to_string(v) +
                         " is out of range (0 fixed, 1 free, 2+k handle k; " + std::to_string(values.size()) +
                         " vertices have at most " + std::to_string(values.size()) + " handles)");
    codes[v] = static_cast<int>(values[v].first);
  }
  return Region::from_codes(std::move(codes));
}

void write_sel(const Region& region, const std::string& path) {
  // Not a file every reader refuses: a handle code skipped (codes 0, 1, 3) fails validate().
  try {
    region.validate(region.num_vertices());
  } catch (const InvalidInput& e) {
    throw InvalidInput("write_sel: " + path + ": " + e.what() + "; nothing was written");
  }
  std::string out = "# " + std::to_string(region.num_vertices()) +
                    " vertices\n# per vertex status: 0=fixed, 1=deformable-region, 2+k=handle k\n";
  for (int c : region.codes()) out += std::to_string(c) + "\n";
  write_file_atomically(path, out);
}

Region read_dmat_groups(const std::string& path, int num_vertices) {
  const auto values = read_numbers<long>(path, "read_dmat_groups", "an integer", std::max(num_vertices, 0) + size_t{2},
                                         "the header '1 " + std::to_string(num_vertices) +
                                             "' (one column, a row per vertex) and one group id per vertex");
  if (values.size() < 2) throw InvalidInput("read_dmat_groups: " + path + ": missing 'cols rows' header");
  const long cols = values[0].first, rows = values[1].first;
  if (cols != 1)
    throw InvalidInput("read_dmat_groups: " + path + ": expected one column of group ids, header says " +
                       std::to_string(cols) + " columns");
  if (rows != num_vertices || static_cast<long>(values.size()) - 2 != rows)
    throw InvalidInput("read_dmat_groups: " + path + ": " + std::to_string(values.size() - 2) + " values (header says " +
                       std::to_string(rows) + ") for a mesh of " + std::to_string(num_vertices) + " vertices");
  std::vector<int> codes(rows);
  for (long v = 0; v < rows; ++v) {
    const long g = values[v + 2].first;
    if (g < -1 || g >= rows)
      throw InvalidInput("read_dmat_groups: " + path + " line " + std::to_string(values[v + 2].second) +
                         ": group " + std::to_string(g) + " is out of range (-1 for free, or a handle index 0.." +
                         std::to_string(rows - 1) + ")");
    codes[v] = g < 0 ? Region::kFree : Region::kFirstHandle + static_cast<int>(g);
  }
  return Region::from_codes(std::move(codes));
}

std::vector<Mat4> read_def(const std::string& path) {
  const auto values = read_numbers<double>(path, "read_def", "a number");
  // Rows of 4 numbers per line, or a whole matrix on one line: a row split over lines (3 then 5 numbers)
  // says the file is not what its writer meant.
  for (size_t i = 0; i < values.size();) {
    const int line = values[i].second;
    size_t n = 0;
    while (i + n < values.size() && values[i + n].second == line) ++n;
    if (!((n == 4 && i % 4 == 0) || (n == 16 && i % 16 == 0)))
      throw InvalidInput("read_def: " + path + " line " + std::to_string(line) + ": " + std::to_string(n) +
                         (n == 1 ? " number" : " numbers") + " starting at entry " + std::to_string(i % 16) +
                         " of matrix " + std::to_string(i / 16) +
                         "; a .def holds each matrix row by row, 4 numbers per line (or 16 on one line)");
    i += n;
  }
  if (values.empty() || values.size() % 16 != 0)
    throw InvalidInput("read_def: " + path + " has " + std::to_string(values.size()) +
                       " numbers; expected one 4x4 matrix (16 numbers, row by row) per handle");
  std::vector<Mat4> out(values.size() / 16);
  for (size_t h = 0; h < out.size(); ++h) {
    for (int k = 0; k < 16; ++k) {
      const auto& [x, line] = values[16 * h + k];
      if (!std::isfinite(x))
        throw InvalidInput("read_def: " + path + " line " + std::to_string(line) + ": non-finite matrix entry");
      out[h](k / 4, k % 4) = x;
    }
    if ((out[h].row(3) - Eigen::RowVector4d(0, 0, 0, 1)).cwiseAbs().maxCoeff() > 1e-9)
      throw InvalidInput("read_def: " + path + " line " + std::to_string(values[16 * h + 12].second) + ": matrix " +
                         std::to_string(h) + " is not affine (its last row must be 0 0 0 1)");
  }
  return out;
}

void write_def(const std::vector<Mat4>& transforms, const std::string& path) {
  if (transforms.empty())
    throw InvalidInput("write_def: " + path +
                       ": no transforms to write (a .def holds one 4x4 matrix per handle)");
  for (size_t h = 0; h < transforms.size(); ++h) {  // what read_def refuses is not written
    if (!transforms[h].allFinite())
      throw InvalidInput("write_def: " + path + ": matrix " + std::to_string(h) + " has a non-finite entry");
    if ((transforms[h].row(3) - Eigen::RowVector4d(0, 0, 0, 1)).cwiseAbs().maxCoeff() > 1e-9)
      throw InvalidInput("write_def: " + path + ": matrix " + std::to_string(h) +
                         " is not affine (its last row must be 0 0 0 1)");
  }
  std::ostringstream out;
  out.precision(17);
  for (size_t h = 0; h < transforms.size(); ++h) {
    out << "# 4x4 transformation of handle " << h << "\n";
    for (int r = 0; r < 4; ++r)
      out << transforms[h](r, 0) << ' ' << transforms[h](r, 1) << ' ' << transforms[h](r, 2) << ' ' << transforms[h](r, 3) << '\n';
  }
  write_file_atomically(path, out.str());
}

std::vector<int> select_box(const Positions& P, const Vec3& lo, const Vec3& hi) {
  if (lo.array().isNaN().any() || hi.array().isNaN().any())
    throw InvalidInput("select_box: a corner of the box is NaN");
  for (int k = 0; k < 3; ++k)
    if (lo[k] > hi[k])
      throw InvalidInput(std::string("select_box: the box's ") + "xyz"[k] + " range is empty (" +
                         format_number(lo[k]) + " > " + format_number(hi[k]) +
                         "): give the low corner first");
  std::vector<int> out;
  for (int i = 0; i < P.rows(); ++i)
    if ((P.row(i).transpose().array() >= lo.array()).all() && (P.row(i).transpose().array() <= hi.array()).all())
      out.push_back(i);
  return out;
}

std::vector<int> select_sphere(const Positions& P, const Vec3& center, double radius) {
  if (!center.allFinite() || !(radius >= 0) || !std::isfinite(radius))
    throw InvalidInput(
        "select_sphere: the centre must be finite and the radius finite and >= 0, got radius " +
        format_number(radius));
  std::vector<int> out;
  for (int i = 0; i < P.rows(); ++i)
    if ((P.row(i).transpose() - center).squaredNorm() <= radius * radius) out.push_back(i);
  return out;
}

std::vector<int> select_halfspace(const Positions& P, const Vec3& point, const Vec3& normal) {
  if (!point.allFinite() || !normal.allFinite() || normal.cwiseAbs().maxCoeff() == 0)
    throw InvalidInput("select_halfspace: the point and normal must be finite and the normal not zero");
  std::vector<int> out;
  for (int i = 0; i < P.rows(); ++i)
    if ((P.row(i).transpose() - point).dot(normal) >= 0) out.push_back(i);
  return out;
}

}  // namespace msd
