// OpenMesh wants its IO header before any mesh kernel header.
#include <OpenMesh/Core/IO/MeshIO.hh>

#include "core/mesh_io.h"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <string_view>
#include <vector>

#include "core/atomic_file.h"
#include "core/errors.h"

namespace msd {
namespace {

// A polygon soup as read from a file, with the source line of every polygon for error messages.
struct Soup {
  std::vector<Vec3> points;
  std::vector<int> corners, offsets{0}, lines;
};

// Splits text into lines with '#' comments stripped, numbering them from 1.
class LineReader {
 public:
  LineReader(std::string_view text, std::string path) : text_(text), path_(std::move(path)) {}
  // Next line that has content; false at the end of the text.
  bool next(std::string_view& line) {
    while (pos_ < text_.size()) {
      size_t end = text_.find('\n', pos_);
      if (end == std::string_view::npos) end = text_.size();
      line = text_.substr(pos_, end - pos_);
      pos_ = end + 1;
      ++number_;
      if (const size_t hash = line.find('#'); hash != std::string_view::npos) line = line.substr(0, hash);
      while (!line.empty() && std::isspace(static_cast<unsigned char>(line.back()))) line.remove_suffix(1);
      while (!line.empty() && std::isspace(static_cast<unsigned char>(line.front()))) line.remove_prefix(1);
      if (!line.empty()) return true;
    }
    return false;
  }
  int number() const { return number_; }
  [[noreturn]] void fail(const std::string& what) const {
    throw InvalidInput("load_mesh: " + path_ + " line " + std::to_string(number_) + ": " + what);
  }

 private:
  std::string_view text_;
  std::string path_;
  size_t pos_ = 0;
  int number_ = 0;
};

// Pops the next whitespace-separated token of line ("" when none is left).
std::string_view next_token(std::string_view& line) {
  size_t b = 0;
  while (b < line.size() && std::isspace(static_cast<unsigned char>(line[b]))) ++b;
  size_t e = b;
  while (e < line.size() && !std::isspace(static_cast<unsigned char>(line[e]))) ++e;
  std::string_view tok = line.substr(b, e - b);
  line.remove_prefix(e);
  return tok;
}

template <class T>
T parse_number(std::string_view tok, const LineReader& reader, const char* what) {
  if (tok.empty()) reader.fail(std::string("missing ") + what);
  T value{};
  const char* first = tok.data();
  if (*first == '+') ++first;
  auto [ptr, ec] = std::from_chars(first, tok.data() + tok.size(), value);
  if (ec != std::errc() || ptr != tok.data() + tok.size())
    reader.fail(std::string("expected ") + what + ", found '" + std::string(tok.substr(0, 40)) + "'");
  return value;
}

Vec3 parse_point(std::string_view& line, const LineReader& reader) {
  Vec3 p;
  for (int k = 0; k < 3; ++k) p[k] = parse_number<double>(next_token(line), reader, "a coordinate");
  if (!p.allFinite()) reader.fail("vertex has a non-finite coordinate (NaN or inf)");
  return p;
}

Soup read_off(std::string_view text, const std::string& path) {
  LineReader reader(text, path);
  std::string_view line;
  if (!reader.next(line)) throw InvalidInput("load_mesh: " + path + " is empty");
  std::string_view head = next_token(line);
  // OFF, COFF, NOFF, CNOFF, STOFF ...: the header ends in "OFF"; "OFF BINARY" is not supported.
  if (head.size() < 3 || head.substr(head.size() - 3) != "OFF" || head.size() > 6)
    reader.fail("not an OFF file: the first line must start with 'OFF'");
  if (!line.empty() && line.find("BINARY") != std::string_view::npos) reader.fail("binary OFF is not supported");
  if (line.empty() && !reader.next(line)) reader.fail("missing vertex and face counts");
  const long nv = parse_number<long>(next_token(line), reader, "the vertex count");
  const long nf = parse_number<long>(next_token(line), reader, "the face count");
  if (nv < 0 || nf < 0) reader.fail("negative vertex or face count");
  Soup soup;
  soup.points.reserve(std::min(nv, 1L << 26));
  for (long i = 0; i < nv; ++i) {
    if (!reader.next(line)) reader.fail("file ends after " + std::to_string(i) + " of " + std::to_string(nv) + " vertices");
    soup.points.push_back(parse_point(line, reader));
  }
  for (long f = 0; f < nf; ++f) {
    if (!reader.next(line)) reader.fail("file ends after " + std::to_string(f) + " of " + std::to_string(nf) + " faces");
    const long n = parse_number<long>(next_token(line), reader, "a face corner count");
    if (n < 3) reader.fail("face " + std::to_string(f) + " has " + std::to_string(n) + " corners (at least 3 needed)");
    for (long k = 0; k < n; ++k) soup.corners.push_back(parse_number<int>(next_token(line), reader, "a vertex index"));
    soup.offsets.push_back(static_cast<int>(soup.corners.size()));
    soup.lines.push_back(reader.number());
  }
  return soup;
}

Soup read_obj(std::string_view text, const std::string& path) {
  LineReader reader(text, path);
  std::string_view line;
  Soup soup;
  while (reader.next(line)) {
    const std::string_view key = next_token(line);
    if (key == "v") {
      soup.points.push_back(parse_point(line, reader));
    } else if (key == "f") {
      const long nv = static_cast<long>(soup.points.size());
      int n = 0;
      for (std::string_view tok = next_token(line); !tok.empty(); tok = next_token(line), ++n) {
        const long idx = parse_number<long>(tok.substr(0, tok.find('/')), reader, "a vertex index");
        if (idx == 0) reader.fail("vertex index 0 (OBJ indices start at 1)");
        // Negative indices count back from the last vertex read so far.
        const long zero_based = idx > 0 ? idx - 1 : nv + idx;
        soup.corners.push_back(static_cast<int>(std::clamp(zero_based, -1L, static_cast<long>(INT32_MAX))));
      }
      if (n < 3) reader.fail("face has " + std::to_string(n) + " corners (at least 3 needed)");
      soup.offsets.push_back(static_cast<int>(soup.corners.size()));
      soup.lines.push_back(reader.number());
    }
    // vt, vn, g, o, s, usemtl, mtllib, l ...: not geometry we use.
  }
  return soup;
}

// PLY, ASCII or binary: vertex x, y, z and the face index lists; other properties and elements are
// skipped. Our own reader because OpenMesh's stores coordinates in single precision.
class PlyReader {
 public:
  PlyReader(std::string_view text, std::string path) : text_(text), path_(std::move(path)) {}

  Soup read() {
    parse_header();
    Soup soup;
    for (const Element& e : elements_) {
      for (long i = 0; i < e.count; ++i) {
        Vec3 p = Vec3::Zero();
        for (size_t k = 0; k < e.props.size(); ++k) {
          const Property& prop = e.props[k];
          if (prop.list_count_type.empty()) {
            const double x = value(prop.type);
            if (e.name == "vertex" && prop.coordinate >= 0) p[prop.coordinate] = x;
            continue;
          }
          const long n = static_cast<long>(value(prop.list_count_type));
          if (n < 0 || n > (1 << 20)) fail("list of " + std::to_string(n) + " items");
          const bool indices = e.name == "face" && (prop.name == "vertex_indices" || prop.name == "vertex_index");
          if (indices && n < 3) fail("face " + std::to_string(i) + " has " + std::to_string(n) + " corners");
          for (long j = 0; j < n; ++j) {
            const double idx = value(prop.type);
            if (indices) soup.corners.push_back(idx >= 0 && idx < 2147483647.0 ? static_cast<int>(idx) : -1);
          }
          if (indices) {
            soup.offsets.push_back(static_cast<int>(soup.corners.size()));
            soup.lines.push_back(0);
          }
        }
        if (e.name == "vertex") {
          if (!p.allFinite()) fail("vertex " + std::to_string(i) + " has a non-finite coordinate (NaN or inf)");
          soup.points.push_back(p);
        }
      }
    }
    return soup;
  }

 private:
  struct Property {
    std::string name, type, list_count_type;
    int coordinate = -1;  // 0, 1, 2 for x, y, z of a vertex
  };
  struct Element {
    std::string name;
    long count = 0;
    std::vector<Property> props;
  };

  [[noreturn]] void fail(const std::string& what) const {
    throw InvalidInput("load_mesh: " + path_ + (binary_ ? "" : " line " + std::to_string(line_)) + ": " + what);
  }

  std::string_view header_token(std::string_view& line) { return next_token(line); }

  void parse_header() {
    if (text_.substr(0, 3) != "ply") throw InvalidInput("load_mesh: " + path_ + " is not a PLY file (it does not start with 'ply')");
    while (true) {
      const size_t end = text_.find('\n', pos_);
      if (end == std::string_view::npos) fail("header has no 'end_header'");
      std::string_view line = text_.substr(pos_, end - pos_);
      pos_ = end + 1;
      ++line_;
      if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
      const std::string_view key = next_token(line);
      if (key == "format") {
        const std::string_view f = next_token(line);
        if (f == "ascii") binary_ = false;
        else if (f == "binary_little_endian") binary_ = true;
        else fail("unsupported PLY format '" + std::string(f) + "'");
      } else if (key == "element") {
        Element e;
        e.name = std::string(next_token(line));
        std::string_view count = next_token(line);
        auto [ptr, ec] = std::from_chars(count.data(), count.data() + count.size(), e.count);
        if (ec != std::errc() || e.count < 0) fail("bad element count '" + std::string(count) + "'");
        elements_.push_back(e);
      } else if (key == "property") {
        if (elements_.empty()) fail("property before any element");
        Property prop;
        std::string_view type = next_token(line);
        if (type == "list") {
          prop.list_count_type = std::string(next_token(line));
          type = next_token(line);
          check_type(prop.list_count_type);
        }
        prop.type = std::string(type);
        check_type(prop.type);
        prop.name = std::string(next_token(line));
        if (elements_.back().name == "vertex" && prop.list_count_type.empty() && prop.name.size() == 1 &&
            prop.name[0] >= 'x' && prop.name[0] <= 'z')
          prop.coordinate = prop.name[0] - 'x';
        elements_.back().props.push_back(prop);
      } else if (key == "end_header") {
        break;
      }
      // comment, obj_info: nothing to do
    }
  }

  void check_type(const std::string& t) const {
    static const char* known[] = {"char", "uchar", "short", "ushort", "int", "uint", "float", "double",
                                  "int8", "uint8", "int16", "uint16", "int32", "uint32", "float32", "float64"};
    for (const char* k : known)
      if (t == k) return;
    fail("unknown PLY property type '" + t + "'");
  }

  double value(const std::string& type) {
    if (!binary_) {
      // ASCII: next whitespace-separated token, counting lines.
      while (pos_ < text_.size() && std::isspace(static_cast<unsigned char>(text_[pos_]))) line_ += text_[pos_++] == '\n';
      size_t e = pos_;
      while (e < text_.size() && !std::isspace(static_cast<unsigned char>(text_[e]))) ++e;
      if (e == pos_) fail("file ends inside the data");
      double x = 0;
      const char* first = text_.data() + pos_;
      auto [ptr, ec] = std::from_chars(first, text_.data() + e, x);
      if (ec != std::errc() || ptr != text_.data() + e)
        fail("expected a number, found '" + std::string(text_.substr(pos_, std::min<size_t>(e - pos_, 40))) + "'");
      pos_ = e;
      return x;
    }
    auto take = [&](auto v) {
      if (pos_ + sizeof(v) > text_.size()) fail("file ends inside the binary data");
      std::memcpy(&v, text_.data() + pos_, sizeof(v));
      pos_ += sizeof(v);
      return static_cast<double>(v);
    };
    if (type == "char" || type == "int8") return take(std::int8_t{});
    if (type == "uchar" || type == "uint8") return take(std::uint8_t{});
    if (type == "short" || type == "int16") return take(std::int16_t{});
    if (type == "ushort" || type == "uint16") return take(std::uint16_t{});
    if (type == "int" || type == "int32") return take(std::int32_t{});
    if (type == "uint" || type == "uint32") return take(std::uint32_t{});
    if (type == "float" || type == "float32") return take(float{});
    return take(double{});
  }

  std::string_view text_;
  std::string path_;
  size_t pos_ = 0;
  int line_ = 0;
  bool binary_ = false;
  std::vector<Element> elements_;
};

Soup read_stl(const std::string& path, std::string_view text) {
  // Check the magic ourselves: OpenMesh's reader only says "failed".
  if (text.substr(0, 5) != "solid") {
    if (text.size() < 84) throw InvalidInput("load_mesh: " + path + " is too short to be a binary STL file");
    std::uint32_t count;
    std::memcpy(&count, text.data() + 80, 4);
    if (text.size() != 84 + 50ull * count)
      throw InvalidInput("load_mesh: " + path + " is not an STL file (binary size does not match its " +
                         std::to_string(count) + " triangles, and it does not start with 'solid')");
  }
  Mesh mesh;
  OpenMesh::IO::Options opt;
  omerr().disable();
  omlog().disable();
  const bool ok = OpenMesh::IO::read_mesh(mesh, path, opt);
  omerr().enable();
  omlog().enable();
  if (!ok) throw InvalidInput("load_mesh: " + path + " could not be parsed as STL (malformed file)");
  Soup soup;
  for (auto v : mesh.vertices()) {
    const auto& p = mesh.point(v);
    soup.points.emplace_back(p[0], p[1], p[2]);
  }
  for (auto f : mesh.faces()) {
    for (auto v : mesh.fv_range(f)) soup.corners.push_back(v.idx());
    soup.offsets.push_back(static_cast<int>(soup.corners.size()));
    soup.lines.push_back(0);
  }
  for (size_t i = 0; i < soup.points.size(); ++i)
    if (!soup.points[i].allFinite())
      throw InvalidInput("load_mesh: " + path + ": vertex " + std::to_string(i) + " has a non-finite coordinate");
  return soup;
}

Mesh build_mesh(const Soup& soup, const std::string& path, LoadReport& report) {
  const int nv = static_cast<int>(soup.points.size());
  const int npoly = static_cast<int>(soup.offsets.size()) - 1;
  if (nv == 0) throw InvalidInput("load_mesh: " + path + " has no vertices");
  if (npoly == 0) throw InvalidInput("load_mesh: " + path + " has no faces (a point cloud is not a mesh)");
  auto where = [&](int f) {
    return path + (soup.lines[f] > 0 ? " line " + std::to_string(soup.lines[f]) : "") + ": face " + std::to_string(f);
  };
  Mesh mesh;
  mesh.reserve(nv, 3 * npoly, 2 * npoly);
  for (const Vec3& p : soup.points) mesh.add_vertex(Mesh::Point(p[0], p[1], p[2]));
  omerr().disable();  // OpenMesh prints a line per non-manifold face; we count them instead
  std::vector<Mesh::VertexHandle> corner;
  for (int f = 0; f < npoly; ++f) {
    corner.clear();
    for (int k = soup.offsets[f]; k < soup.offsets[f + 1]; ++k) {
      const int idx = soup.corners[k];
      if (idx < 0 || idx >= nv) {
        omerr().enable();
        throw InvalidInput("load_mesh: " + where(f) + " has vertex index " + std::to_string(idx) +
                           " out of range [0, " + std::to_string(nv) + ")");
      }
      corner.push_back(mesh.vertex_handle(idx));
    }
    std::vector<Mesh::VertexHandle> sorted = corner;
    std::sort(sorted.begin(), sorted.end());
    if (std::adjacent_find(sorted.begin(), sorted.end()) != sorted.end()) {
      ++report.degenerate_faces_skipped;
      continue;
    }
    if (corner.size() > 3) ++report.polygons_triangulated;
    for (size_t k = 1; k + 1 < corner.size(); ++k) {
      Mesh::VertexHandle tri[3] = {corner[0], corner[k], corner[k + 1]};
      if (mesh.add_face(tri[0], tri[1], tri[2]).is_valid()) continue;
      ++report.nonmanifold_faces;
      for (auto& v : tri) {
        // A copy: add_vertex may reallocate the point array that mesh.point(v) refers into.
        const Mesh::Point p = mesh.point(v);
        v = mesh.add_vertex(p);
        ++report.duplicated_vertices;
      }
      mesh.add_face(tri[0], tri[1], tri[2]);
    }
  }
  omerr().enable();
  if (mesh.n_faces() == 0) throw InvalidInput("load_mesh: " + path + " has no valid faces (all are degenerate)");
  return mesh;
}

// Shortest decimal that reads back to the same double.
void append_number(std::string& out, double x) {
  char buf[32];
  auto [ptr, ec] = std::to_chars(buf, buf + sizeof(buf), x);
  out.append(buf, ptr);
}
void append_number(std::string& out, long x) {
  char buf[24];
  auto [ptr, ec] = std::to_chars(buf, buf + sizeof(buf), x);
  out.append(buf, ptr);
}

void append_point(std::string& out, const Positions& P, Eigen::Index i) {
  append_number(out, P(i, 0));
  out += ' ';
  append_number(out, P(i, 1));
  out += ' ';
  append_number(out, P(i, 2));
}

}  // namespace

std::string file_extension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext;
}

Mesh load_mesh(const std::string& path, LoadReport* report) {
  const std::string ext = file_extension(path);
  if (ext != ".off" && ext != ".obj" && ext != ".ply" && ext != ".stl")
    throw InvalidInput("load_mesh: " + path + ": unknown format '" + ext + "' (supported: .off .obj .ply .stl)");
  if (std::filesystem::is_directory(path)) throw InvalidInput("load_mesh: " + path + " is a folder, not a mesh file");
  const std::string text = read_file(path, "load_mesh");
  Soup soup;
  if (ext == ".off")
    soup = read_off(text, path);
  else if (ext == ".obj")
    soup = read_obj(text, path);
  else if (ext == ".ply")
    soup = PlyReader(text, path).read();
  else
    soup = read_stl(path, text);
  LoadReport local;
  Mesh mesh = build_mesh(soup, path, report ? *report : local);
  return mesh;
}

void save_mesh(const Positions& P, const Faces& F, const std::string& path, const SaveOptions& options) {
  const std::string ext = file_extension(path);
  if (ext != ".off" && ext != ".obj" && ext != ".ply" && ext != ".stl")
    throw InvalidInput("save_mesh: " + path + ": unknown format '" + ext + "' (supported: .off .obj .ply .stl)");
  if (!P.allFinite()) throw InvalidInput("save_mesh: " + path + ": positions contain NaN or inf; nothing written");
  if (options.vertex_scalar) {
    if (ext != ".ply") throw InvalidInput("save_mesh: " + path + ": per-vertex scalars need the .ply format");
    if (options.vertex_scalar->size() != P.rows())
      throw InvalidInput("save_mesh: " + path + ": " + std::to_string(options.vertex_scalar->size()) +
                         " scalars for " + std::to_string(P.rows()) + " vertices");
  }
  const long nv = P.rows(), nf = F.rows();
  std::string out;
  out.reserve(static_cast<size_t>(nv) * 64 + static_cast<size_t>(nf) * 32 + 256);
  if (ext == ".stl") {
    out.assign(80, '\0');
    std::memcpy(out.data(), "msdeform binary STL", 19);
    const std::uint32_t count = static_cast<std::uint32_t>(nf);
    out.append(reinterpret_cast<const char*>(&count), 4);
    for (long f = 0; f < nf; ++f) {
      const Vec3 a = P.row(F(f, 0)), b = P.row(F(f, 1)), c = P.row(F(f, 2));
      Vec3 n = (b - a).cross(c - a);
      if (n.norm() > 0) n.normalize();
      float buf[12];
      for (int k = 0; k < 3; ++k) {
        buf[k] = static_cast<float>(n[k]);
        buf[3 + k] = static_cast<float>(a[k]);
        buf[6 + k] = static_cast<float>(b[k]);
        buf[9 + k] = static_cast<float>(c[k]);
      }
      out.append(reinterpret_cast<const char*>(buf), sizeof(buf));
      out.append(2, '\0');
    }
  } else if (ext == ".off") {
    out += "OFF\n";
    append_number(out, nv);
    out += ' ';
    append_number(out, nf);
    out += " 0\n";
    for (long i = 0; i < nv; ++i) append_point(out, P, i), out += '\n';
    for (long f = 0; f < nf; ++f) {
      out += "3";
      for (int k = 0; k < 3; ++k) out += ' ', append_number(out, static_cast<long>(F(f, k)));
      out += '\n';
    }
  } else if (ext == ".obj") {
    out += "# written by msdeform\n";
    for (long i = 0; i < nv; ++i) out += "v ", append_point(out, P, i), out += '\n';
    for (long f = 0; f < nf; ++f) {
      out += "f";
      for (int k = 0; k < 3; ++k) out += ' ', append_number(out, static_cast<long>(F(f, k)) + 1);
      out += '\n';
    }
  } else {  // .ply, ASCII
    out += "ply\nformat ascii 1.0\ncomment written by msdeform\nelement vertex ";
    append_number(out, nv);
    out += "\nproperty double x\nproperty double y\nproperty double z\n";
    if (options.vertex_scalar) out += "property double " + options.scalar_name + "\n";
    out += "element face ";
    append_number(out, nf);
    out += "\nproperty list uchar int vertex_indices\nend_header\n";
    for (long i = 0; i < nv; ++i) {
      append_point(out, P, i);
      if (options.vertex_scalar) out += ' ', append_number(out, (*options.vertex_scalar)[i]);
      out += '\n';
    }
    for (long f = 0; f < nf; ++f) {
      out += "3";
      for (int k = 0; k < 3; ++k) out += ' ', append_number(out, static_cast<long>(F(f, k)));
      out += '\n';
    }
  }
  write_file_atomically(path, out);
}

void save_mesh(const Mesh& mesh, const std::string& path, const SaveOptions& options) {
  save_mesh(positions(mesh), faces(mesh), path, options);
}

}  // namespace msd
