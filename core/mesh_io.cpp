#include "msdeform/core/mesh_io.h"

#include <OpenMesh/Core/System/omstream.hh>

#include <algorithm>
#include <array>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <limits>
#include <numeric>
#include <sstream>
#include <string_view>
#include <unordered_map>
#include <vector>

#include "msdeform/core/atomic_file.h"
#include "msdeform/core/errors.h"
#include "msdeform/core/extent.h"
#include "msdeform/core/surface_check.h"

namespace msd {
namespace {

// A file's vertices and polygons as read, with the source line of every polygon for error messages.
struct FileContents {
  std::vector<Vec3> points;
  std::vector<double> vertex_property;  // PLY: the values of the property asked for (PlyReader)
  std::vector<int> corners, offsets{0}, lines;
  int first_ignored_line = 0;  // OFF and ASCII PLY: the first line of data after the header's counts
  // LoadReport::first_attribute_line: OFF's first record with numbers past its coordinates or indices,
  // OBJ's first vt, vn, usemtl, mtllib, l or p or vertex colour, PLY's first header line read past
  int first_attribute_line = 0;
};

// Longest line a text reader looks through for its end: a text file's line is far shorter, so a bad file
// (binary data, gigabytes without a break) fails after this much instead of being scanned whole.
constexpr size_t kMaxLine = size_t{64} << 20;

enum class LineEnd { Break, EndOfText, TooLong };

// The line of text that starts at pos, without its break (LF, CR LF or CR); pos moves past the break.
// EndOfText, leaving pos, when no break follows (the line runs to the end of the text); TooLong when no
// break comes within kMaxLine bytes.
LineEnd take_line(std::string_view text, size_t& pos, std::string_view& line) {
  const std::string_view window = text.substr(pos, kMaxLine + 1);
  const size_t end = window.find_first_of("\r\n");
  line = window.substr(0, end);
  if (end == std::string_view::npos) return window.size() > kMaxLine ? LineEnd::TooLong : LineEnd::EndOfText;
  pos += end + (window.substr(end, 2) == "\r\n" ? 2 : 1);
  return LineEnd::Break;
}

std::string too_long_message() {
  return "no line break within " + std::to_string(kMaxLine >> 20) + " MiB (binary data, or not a text file)";
}

// Splits text into lines with '#' comments stripped, numbering them from 1. Lines end in LF, CR LF or CR.
class LineReader {
 public:
  // who: the public function reading, named in messages
  LineReader(std::string_view text, std::string path, std::string who)
      : text_(text), path_(std::move(path)), who_(std::move(who)) {}
  // Next line that has content; false at the end of the text.
  bool next(std::string_view& line) {
    while (pos_ < text_.size()) {
      const LineEnd end = take_line(text_, pos_, line);
      ++number_;
      if (end == LineEnd::TooLong) fail(too_long_message());
      if (end == LineEnd::EndOfText) pos_ = text_.size();  // the last line, without a break
      if (const size_t hash = line.find('#'); hash != std::string_view::npos) line = line.substr(0, hash);
      while (!line.empty() && std::isspace(static_cast<unsigned char>(line.back()))) line.remove_suffix(1);
      while (!line.empty() && std::isspace(static_cast<unsigned char>(line.front()))) line.remove_prefix(1);
      if (!line.empty()) return true;
    }
    return false;
  }
  int number() const { return number_; }
  // Bytes after the current line.
  size_t bytes_left() const { return pos_ < text_.size() ? text_.size() - pos_ : 0; }
  [[noreturn]] void fail(const std::string& what) const {
    throw InvalidInput(who_ + ": " + path_ + " line " + std::to_string(number_) + ": " + what);
  }

 private:
  std::string_view text_;
  std::string path_, who_;
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
  if (ec == std::errc::result_out_of_range && ptr == tok.data() + tok.size())
    reader.fail(std::string(what) + " '" + printable(tok.substr(0, 40)) + "' is out of range");
  if (ec != std::errc() || ptr != tok.data() + tok.size())
    reader.fail(std::string("expected ") + what + ", found '" + printable(tok.substr(0, 40)) + "'");
  return value;
}

// Reads past the rest of an OFF record, the colour or normal numbers after a vertex's coordinates or a
// face's indices: whether there were any. \throw (reader.fail) for a token that is not a number, naming it
// and the record ("vertex" or "face" `index`, whose `fields` the numbers follow).
bool skip_attributes(std::string_view& line, const LineReader& reader, const char* record, long index,
                     const char* fields) {
  bool any = false;
  for (std::string_view tok = next_token(line); !tok.empty(); tok = next_token(line), any = true) {
    double value;
    const char* first = tok.data() + (tok[0] == '+');
    const auto [ptr, ec] = std::from_chars(first, tok.data() + tok.size(), value);
    if (ptr != tok.data() + tok.size() || (ec != std::errc() && ec != std::errc::result_out_of_range))
      reader.fail("'" + printable(tok.substr(0, 40)) + "' after " + record + " " + std::to_string(index) +
                  "'s " + fields + " is not a number (only colour or normal numbers may follow them)");
  }
  return any;
}

Vec3 parse_point(std::string_view& line, const LineReader& reader) {
  Vec3 p;
  for (int k = 0; k < 3; ++k) p[k] = parse_number<double>(next_token(line), reader, "a coordinate");
  if (!p.allFinite()) reader.fail("vertex has a non-finite coordinate (NaN or inf)");
  return p;
}

// The next token of a record: records that a writer wrapped continue on the following lines (`wrapped`
// is then set).
std::string_view record_token(LineReader& reader, std::string_view& line, bool& wrapped) {
  std::string_view tok = next_token(line);
  while (tok.empty() && reader.next(line)) {
    tok = next_token(line);
    wrapped = true;
  }
  return tok;
}

// A wrapped record must end where its last line ends: numbers left over there mean that the record's
// first line lacked one (a vertex line "1 0" would otherwise take its z from the next vertex and shift
// every record after it).
void check_wrapped_record_end(const LineReader& reader, std::string_view line, bool wrapped, const char* kind,
                              long index, int first_line) {
  if (wrapped && !next_token(line).empty())
    reader.fail(std::string(kind) + " " + std::to_string(index) + " starts on line " + std::to_string(first_line) + " with too few numbers and runs into this "
                "line, which holds more than the rest of it: is a number missing on line " +
                std::to_string(first_line) + "?");
}

FileContents read_off(std::string_view text, const std::string& path, const std::string& who) {
  LineReader reader(text, path, who);
  std::string_view line;
  if (!reader.next(line)) throw InvalidInput(who + ": " + path + " is empty");
  std::string_view head = next_token(line);
  // OFF, COFF, NOFF, CNOFF, STOFF, STCNOFF, 4OFF, nOFF ...: a prefix of the letters S, T, C, N, 4, n (in
  // the order [ST][C][N][4][n]), then "OFF". Some writers (ModelNet) glue the vertex count to it: "OFF8 6 0".
  const size_t off = head.find("OFF");
  if (off == std::string_view::npos || off > 6 ||
      head.substr(0, off).find_first_not_of("STCN4n") != std::string_view::npos)
    reader.fail("not an OFF file: the first line must start with 'OFF' (or COFF, NOFF, ...), found '" +
                printable(head.substr(0, 40)) + "'");
  // 4OFF's fourth coordinate is a homogeneous w, nOFF's dimension is not 3: read as plain OFF, both are wrong.
  if (head.substr(0, off).find_first_of("4n") != std::string_view::npos)
    reader.fail("'" + printable(head.substr(0, off + 3)) + "' (homogeneous or n-dimensional coordinates) is not "
                "supported; only OFF with 3 coordinates per vertex (and COFF, NOFF, STOFF) is");
  std::string_view glued = head.substr(off + 3);
  if (!glued.empty() && !std::isdigit(static_cast<unsigned char>(glued[0])))
    reader.fail("not an OFF file: the header '" + printable(head.substr(0, 40)) + "' is not OFF followed by counts");
  if (!line.empty() && line.find("BINARY") != std::string_view::npos) reader.fail("binary OFF is not supported");
  if (glued.empty() && line.empty() && !reader.next(line)) reader.fail("missing vertex and face counts");
  const long nv = parse_number<long>(glued.empty() ? next_token(line) : glued, reader, "the vertex count");
  const long nf = parse_number<long>(next_token(line), reader, "the face count");
  if (nv < 0 || nf < 0) reader.fail("negative vertex or face count");
  // The edge count (optional, unused), then nothing: records start on the next line, one per line.
  next_token(line);
  if (const std::string_view rest = next_token(line); !rest.empty())
    reader.fail("the counts line goes on after the vertex, face and edge counts with '" +
                printable(rest.substr(0, 40)) +
                "'; an OFF file has one vertex or face per line, starting on "
                "the line after the counts");
  // A vertex takes at least 6 bytes ("0 0 0\n"), a face record at least 2 (its corner count: a face with too
  // few corners is then named by the face reader, not taken for a short file); the last line may lack its
  // newline. Counts the rest of the file cannot hold are refused before anything is allocated.
  const size_t left = reader.bytes_left() + 1;
  if (static_cast<unsigned long>(nv) > left / 6 || static_cast<unsigned long>(nf) > left / 2 ||
      6 * static_cast<unsigned long>(nv) + 2 * static_cast<unsigned long>(nf) > left)
    reader.fail("the header declares " + std::to_string(nv) + " vertices and " + std::to_string(nf) +
                " faces, but only " + std::to_string(left - 1) + " bytes follow");
  FileContents soup;
  soup.points.reserve(static_cast<size_t>(nv));
  int extra_line = 0;  // a vertex line with more than three numbers (colours, or vertices that share lines)
  long extra_vertex = 0;  // its vertex
  for (long i = 0; i < nv; ++i) {
    if (!reader.next(line)) {
      std::string why;
      if (extra_line > 0)
        why = " (line " + std::to_string(extra_line) + " has more than three numbers: one vertex per line is "
              "read, the rest of a line as its colour or normal)";
      reader.fail("file ends after " + std::to_string(i) + " of " + std::to_string(nv) + " vertices" + why);
    }
    Vec3 p;
    const int first_line = reader.number();
    bool wrapped = false;
    for (int k = 0; k < 3; ++k)
      p[k] = parse_number<double>(record_token(reader, line, wrapped), reader, "a coordinate");
    if (!p.allFinite()) reader.fail("vertex has a non-finite coordinate (NaN or inf)");
    check_wrapped_record_end(reader, line, wrapped, "vertex", i, first_line);
    if (skip_attributes(line, reader, "vertex", i, "coordinates") && extra_line == 0)
      extra_line = reader.number(), extra_vertex = i;
    soup.points.push_back(p);
  }
  for (long f = 0; f < nf; ++f) {
    if (!reader.next(line)) {
      // Vertices with three numbers, then some with more: face lines read as vertices, if the header counts
      // vertices that are not there.
      std::string why;
      if (extra_vertex > 0)
        why = " (vertices 0 to " + std::to_string(extra_vertex - 1) + " have three numbers, vertex " +
              std::to_string(extra_vertex) + " on line " + std::to_string(extra_line) +
              " more: if the header's vertex count " + std::to_string(nv) +
              " is too large, face lines were read as vertices from there)";
      reader.fail("file ends after " + std::to_string(f) + " of " + std::to_string(nf) + " faces" + why);
    }
    const long n = parse_number<long>(next_token(line), reader, "a face corner count");
    if (n < 3) reader.fail("face " + std::to_string(f) + " has " + std::to_string(n) + " corners (at least 3 needed)");
    if (static_cast<unsigned long>(n) > reader.bytes_left() + line.size())
      reader.fail("face " + std::to_string(f) + " has " + std::to_string(n) + " corners, more than the file holds");
    const int first_line = reader.number();
    bool wrapped = false;
    for (long k = 0; k < n; ++k)
      soup.corners.push_back(parse_number<int>(record_token(reader, line, wrapped), reader, "a vertex index"));
    check_wrapped_record_end(reader, line, wrapped, "face", f, first_line);
    if (!wrapped && skip_attributes(line, reader, "face", f, "indices") && soup.first_attribute_line == 0)
      soup.first_attribute_line = reader.number();  // a face colour
    soup.offsets.push_back(static_cast<int>(soup.corners.size()));
    soup.lines.push_back(reader.number());
  }
  // More records than the header counts (CGAL's prim.off has a face too many): read as counted, as
  // other readers do, and reported.
  if (reader.next(line)) soup.first_ignored_line = reader.number();
  if (extra_line > 0 && (soup.first_attribute_line == 0 || extra_line < soup.first_attribute_line))
    soup.first_attribute_line = extra_line;  // vertex colours or normals
  return soup;
}

FileContents read_obj(std::string_view text, const std::string& path, const std::string& who) {
  LineReader reader(text, path, who);
  std::string_view line;
  FileContents soup;
  while (reader.next(line)) {
    const std::string_view key = next_token(line);
    if (key == "v") {
      soup.points.push_back(parse_point(line, reader));
      // x y z r g b (or x y z w r g b): a vertex colour; a lone fourth number is the rational weight w.
      // Numbers all (a word there was read without a word, third break test).
      int extra = 0;
      for (std::string_view tok = next_token(line); !tok.empty(); tok = next_token(line), ++extra)
        parse_number<double>(tok, reader, "a number (a vertex colour or weight)");
      if (extra >= 2 && soup.first_attribute_line == 0) soup.first_attribute_line = reader.number();
    } else if (key == "f") {
      const long nv = static_cast<long>(soup.points.size());
      int n = 0;
      for (std::string_view tok = next_token(line); !tok.empty(); tok = next_token(line), ++n) {
        const long idx = parse_number<long>(tok.substr(0, tok.find('/')), reader, "a vertex index");
        // v/vt/vn, v//vn, v/vt: the texture and normal indices are not used, but must be numbers.
        for (size_t slash = tok.find('/'); slash != std::string_view::npos;) {
          const size_t next = tok.find('/', slash + 1);
          const std::string_view part = tok.substr(slash + 1, next == std::string_view::npos ? next : next - slash - 1);
          if (!part.empty() || next == std::string_view::npos) parse_number<long>(part, reader, "a texture or normal index");
          slash = next;
        }
        if (idx == 0) reader.fail("vertex index 0 (OBJ indices start at 1)");
        if (idx < -nv) reader.fail("relative vertex index " + std::to_string(idx) + " reaches before the first vertex (" +
                                   std::to_string(nv) + " vertices so far)");
        if (idx > INT32_MAX) reader.fail("vertex index " + std::to_string(idx) + " is out of range");
        // Negative indices count back from the last vertex read so far; positive ones may name a vertex
        // defined later in the file (checked below).
        soup.corners.push_back(static_cast<int>(idx > 0 ? idx - 1 : nv + idx));
      }
      if (n < 3) reader.fail("face has " + std::to_string(n) + " corners (at least 3 needed)");
      soup.offsets.push_back(static_cast<int>(soup.corners.size()));
      soup.lines.push_back(reader.number());
    }
    // vt, vn, g, o, s, usemtl, mtllib, l ...: not geometry we use. A statement that is not a word is
    // not OBJ (binary data, another format): stop at it rather than skip the whole file.
    else if (key.size() > 16 || !std::all_of(key.begin(), key.end(), [](char c) {
               return std::isalnum(static_cast<unsigned char>(c)) || c == '_';
             }))
      reader.fail("not an OBJ statement: '" + printable(key.substr(0, 40)) + "'");
    // Texture coordinates, normals, materials, lines and points a written result will not have.
    else if ((key == "vt" || key == "vn" || key == "usemtl" || key == "mtllib" || key == "l" || key == "p") &&
             soup.first_attribute_line == 0)
      soup.first_attribute_line = reader.number();
  }
  // Indices in OBJ's own numbering (from 1), so the message matches the file.
  for (size_t f = 0; f + 1 < soup.offsets.size(); ++f)
    for (int c = soup.offsets[f]; c < soup.offsets[f + 1]; ++c)
      if (soup.corners[c] >= static_cast<int>(soup.points.size()))
        throw InvalidInput(who + ": " + path + " line " + std::to_string(soup.lines[f]) + ": face has vertex index " +
                           std::to_string(soup.corners[c] + 1) + ", out of range: the file has " +
                           std::to_string(soup.points.size()) + " vertices (OBJ indices start at 1)");
  return soup;
}

// PLY, ASCII or binary: vertex x, y, z and the face index lists; other properties and elements are
// skipped. Our own reader because OpenMesh's stores coordinates in single precision.
class PlyReader {
 public:
  // property: the name of a vertex property whose values read() keeps (empty: none).
  PlyReader(std::string_view text, std::string path, std::string who, std::string property = {})
      : text_(text), path_(std::move(path)), who_(std::move(who)), property_(std::move(property)) {}

  FileContents read() {
    parse_header();
    FileContents soup;
    for (const Element& e : elements_) {
      if (e.props.empty()) continue;
      for (long i = 0; i < e.count; ++i) {
        if (!binary_) skip_space();
        const int item_line = line_;
        Vec3 p = Vec3::Zero();
        for (const Property& prop : e.props) {
          if (prop.list_count_type.empty()) {
            const double x = value(prop.type);
            if (e.name == "vertex" && prop.coordinate >= 0) p[prop.coordinate] = x;
            if (e.name == "vertex" && !property_.empty() && prop.name == property_) soup.vertex_property.push_back(x);
            continue;
          }
          const double n = value(prop.list_count_type);  // an integer type (parse_header)
          if (e.name == "tristrips" && prop.corners()) {
            read_strips(n, prop.type, i, item_line, soup);
            continue;
          }
          const bool indices = e.name == "face" && prop.corners();
          // Written so that NaN fails too; a fractional count is not an integer either.
          if (!(n >= (indices ? 3 : 0) && n <= (1 << 20)) || n != std::floor(n))
            fail(e.name + " " + std::to_string(i) + " has a list of " + number(n) +
                 " items" + (indices ? " (a face needs 3 to 2^20 corners)" : " (a whole number, at most 2^20)"));
          for (int j = 0; j < static_cast<int>(n); ++j) {
            const double idx = value(prop.type);
            if (!indices) continue;
            if (idx != std::floor(idx) || idx < -1e15 || idx > 1e15)
              fail("face " + std::to_string(i) + " has vertex index " + number(idx) + ", not an integer");
            // Beyond int, said here with the file's value (a uint 4294967295 was named as 2147483647); the
            // rest out of range are reported with the face by triangulate (as for OFF and OBJ).
            if (idx < -2147483648.0 || idx > 2147483647.0)
              fail("face " + std::to_string(i) + " has vertex index " + number(idx) + ", out of range");
            soup.corners.push_back(static_cast<int>(idx));
          }
          if (indices) {
            soup.offsets.push_back(static_cast<int>(soup.corners.size()));
            soup.lines.push_back(binary_ ? 0 : item_line);
          }
        }
        end_item(e, i);
        if (e.name == "vertex") {
          if (!p.allFinite()) fail("vertex " + std::to_string(i) + " has a non-finite coordinate (NaN or inf)");
          soup.points.push_back(p);
        }
      }
      vertices_read_ = vertices_read_ || e.name == "vertex";
    }
    if (!binary_) {
      skip_space();
      if (pos_ < text_.size()) soup.first_ignored_line = line_;
    }
    soup.first_attribute_line = first_unread_line_;
    if (!property_.empty() && soup.vertex_property.size() != soup.points.size()) {
      std::string names;
      for (const Element& e : elements_)
        if (e.name == "vertex")
          for (const Property& prop : e.props) names += (names.empty() ? "" : ", ") + prop.name;
      for (const Element& e : elements_)  // a list by that name: not one value per vertex
        for (const Property& prop : e.props)
          if (e.name == "vertex" && prop.name == property_)
            throw InvalidInput(
                who_ + ": " + path_ + ": the vertex property '" + printable(property_.substr(0, 60)) +
                "' is a list, not one value per vertex (its vertex properties: " + names + ")");
      throw InvalidInput(who_ + ": " + path_ + " has no vertex property '" + printable(property_.substr(0, 60)) +
                         "' (its vertex properties: " + names + ")");
    }
    return soup;
  }

 private:
  struct Property {
    std::string name, type, list_count_type;
    // A list of a polygon's or a strip's corners.
    bool corners() const { return !list_count_type.empty() && (name == "vertex_indices" || name == "vertex_index"); }
    int coordinate = -1;  // 0, 1, 2 for x, y, z of a vertex
  };
  struct Element {
    std::string name;
    long count = 0;
    std::vector<Property> props;
  };

  // Triangle strips (a `tristrips` element, as PLY's original tools write them): a list of n vertex
  // indices, -1 ending a strip; each run of three makes a triangle, every other one turned to keep the
  // strip's orientation. Triangles that repeat a vertex join strips and are left out.
  void read_strips(double n, const std::string& type, long item, int item_line, FileContents& soup) {
    if (!(n >= 0 && n <= (1 << 24)) || n != std::floor(n))
      fail("tristrips " + std::to_string(item) + " has a list of " + number(n) +
           " items (a whole number, at most 2^24)");
    std::vector<int> strip;
    const auto flush = [&] {
      for (size_t k = 2; k < strip.size(); ++k) {
        int a = strip[k - 2], b = strip[k - 1];
        const int c = strip[k];
        if (k % 2 == 1) std::swap(a, b);
        if (a == b || b == c || a == c) continue;
        soup.corners.insert(soup.corners.end(), {a, b, c});
        soup.offsets.push_back(static_cast<int>(soup.corners.size()));
        soup.lines.push_back(binary_ ? 0 : item_line);
      }
      strip.clear();
    };
    // The restart is -1, or in an unsigned list its largest value (0xFFFF, 0xFFFFFFFF), as -1 is written
    // there.
    const double restart = type == "ushort" || type == "uint16" ? 65535.0
                           : type == "uint" || type == "uint32" ? 4294967295.0
                                                                : -1.0;
    for (long j = 0; j < static_cast<long>(n); ++j) {
      double idx = value(type);
      if (idx == restart) idx = -1;
      if (idx != std::floor(idx) || idx < -1 || idx > 2147483647.0)
        fail("tristrips " + std::to_string(item) + " has vertex index " + number(idx) +
             ", not -1 or an index");
      // Named here, as a strip's (the triangles it makes are numbered as faces after the strips are split).
      if (vertices_read_ && idx >= static_cast<double>(soup.points.size()))
        fail("tristrips " + std::to_string(item) + " has vertex index " + number(idx) + " out of range [0, " +
             std::to_string(soup.points.size()) + ")");
      if (idx < 0)
        flush();
      else
        strip.push_back(static_cast<int>(idx));
    }
    flush();
  }

  [[noreturn]] void fail(const std::string& what) const {
    const bool has_lines = !binary_ || in_header_;
    throw InvalidInput(who_ + ": " + path_ + (has_lines ? " line " + std::to_string(line_) : "") + ": " + what);
  }

  std::string_view header_token(std::string_view& line) { return next_token(line); }

  void parse_header() {
    std::string_view first;
    const LineEnd first_end = take_line(text_, pos_, first);
    line_ = 1;
    if (first.substr(0, 3) != "ply")
      throw InvalidInput(who_ + ": " + path_ + " is not a PLY file (it does not start with 'ply')");
    if (first_end == LineEnd::TooLong) fail(too_long_message());
    while (!first.empty() && (first.back() == ' ' || first.back() == '\t')) first.remove_suffix(1);
    if (first != "ply") fail("the first line must be 'ply' alone, found '" + printable(first.substr(0, 40)) + "'");
    bool has_format = false;
    while (true) {
      std::string_view line;
      const LineEnd end = take_line(text_, pos_, line);
      ++line_;
      if (end == LineEnd::TooLong) fail(too_long_message());
      if (end == LineEnd::EndOfText) fail("header has no 'end_header'");
      const std::string_view key = next_token(line);
      // Every header line is parsed whole: a word too many is an error, not ignored.
      const auto end_of_line = [&]() {
        if (const std::string_view extra = next_token(line); !extra.empty())
          fail("unexpected '" + printable(extra.substr(0, 40)) + "' at the end of the '" + std::string(key) + "' line");
      };
      if (key == "format") {
        if (has_format) fail("a second 'format' line");
        has_format = true;
        const std::string_view f = next_token(line);
        binary_ = f != "ascii";
        swap_bytes_ = f == "binary_big_endian";
        if (f != "ascii" && f != "binary_little_endian" && f != "binary_big_endian")
          fail("unknown PLY format '" + printable(f.substr(0, 40)) +
               "' (ascii, binary_little_endian or binary_big_endian)");
        if (next_token(line) != "1.0") fail("unsupported PLY version (1.0 expected)");
        end_of_line();
      } else if (key == "element") {
        Element e;
        e.name = std::string(next_token(line));
        std::string_view count = next_token(line);
        auto [ptr, ec] = std::from_chars(count.data(), count.data() + count.size(), e.count);
        if (ec != std::errc() || ptr != count.data() + count.size() || e.count < 0 || e.name.empty())
          fail("bad element count '" + printable(count.substr(0, 40)) + "'");
        end_of_line();
        elements_.push_back(e);
      } else if (key == "property") {
        if (elements_.empty()) fail("property before any element");
        Property prop;
        std::string_view type = next_token(line);
        if (type == "list") {
          prop.list_count_type = std::string(next_token(line));
          type = next_token(line);
          check_type(prop.list_count_type);
          if (prop.list_count_type.find("float") != std::string::npos || prop.list_count_type == "double")
            fail("a list count of type '" + prop.list_count_type + "' (it must be an integer type)");
        }
        prop.type = std::string(type);
        check_type(prop.type);
        prop.name = std::string(next_token(line));
        if (prop.name.empty()) fail("property without a name");
        end_of_line();
        for (const Property& other : elements_.back().props)
          if (other.name == prop.name)
            fail("element '" + printable(elements_.back().name) + "' has two properties named '" + printable(prop.name) + "'");
        if (elements_.back().name == "vertex" && prop.list_count_type.empty() && prop.name.size() == 1 &&
            prop.name[0] >= 'x' && prop.name[0] <= 'z')
          prop.coordinate = prop.name[0] - 'x';
        const bool read = elements_.back().name == "vertex"
                              ? prop.coordinate >= 0 || prop.name == property_
                              : (elements_.back().name == "face" || elements_.back().name == "tristrips") &&
                                    prop.corners();
        if (!read && first_unread_line_ == 0) first_unread_line_ = line_;  // colours, normals, face data
        elements_.back().props.push_back(prop);
      } else if (key == "end_header") {
        end_of_line();
        if (!has_format) fail("the header has no 'format' line");
        // A face element must list its corners (other names would drop every face without a word).
        for (const Element& e : elements_) {
          if (e.name != "face" || e.count == 0) continue;
          if (std::none_of(e.props.begin(), e.props.end(), [](const Property& prop) { return prop.corners(); }))
            fail("the face element has no list property 'vertex_indices' (or 'vertex_index')");
        }
        // Corners listed by another element (not face or tristrips) would be dropped without a word.
        for (const Element& e : elements_)
          if (e.name != "face" && e.name != "tristrips" && e.count > 0 &&
              std::any_of(e.props.begin(), e.props.end(), [](const Property& prop) { return prop.corners(); }))
            fail("element '" + printable(e.name.substr(0, 40)) +
                 "' lists vertex indices, which msdeform reads only "
                 "from a 'face' element (polygons) or a 'tristrips' element (triangle strips)");
        // A vertex element must have x, y and z (other spellings, e.g. X Y Z, would read as zeros).
        for (const Element& e : elements_) {
          if (e.name != "vertex" || e.count == 0) continue;
          bool has[3] = {false, false, false};
          for (const auto& prop : e.props)
            if (prop.coordinate >= 0) has[prop.coordinate] = true;
          for (int k = 0; k < 3; ++k)
            if (!has[k]) fail(std::string("the vertex element has no property '") + char('x' + k) +
                              "' (properties x, y and z, lower case, give the positions)");
        }
        in_header_ = false;
        ++line_;  // line_ is now the line at pos_, where the data starts
        check_sizes();
        break;
      } else if (key != "comment" && key != "obj_info" && !key.empty()) {
        fail("unknown PLY header keyword '" + printable(key.substr(0, 40)) + "'");
      }
    }
  }

  // Every element count is checked against the bytes after the header (an item takes at least one byte
  // per value, two in ASCII), so a corrupt count fails here instead of allocating or looping for it.
  // Elements without properties take no bytes and are skipped.
  void check_sizes() {
    const double left = static_cast<double>(text_.size() - pos_) + 1;
    double need = 0;
    for (const Element& e : elements_) {
      if (e.props.empty()) continue;
      double item = 0;
      for (const Property& prop : e.props) {
        const double scalar = binary_ ? static_cast<double>(type_size(prop.list_count_type.empty() ? prop.type : prop.list_count_type)) : 2;
        item += scalar;
      }
      const bool first = need == 0;
      need += item * static_cast<double>(e.count);
      if (need > left || e.count > INT32_MAX) {
        char bytes[32];
        std::snprintf(bytes, sizeof bytes, "%.0f", need);
        fail("element '" + printable(e.name) + "' declares " + std::to_string(e.count) + " items, which" +
             (first ? "" : " with the elements before it") + " need at least " + bytes + " bytes, but only " +
             std::to_string(text_.size() - pos_) + " bytes follow the header (an element count is too large, "
             "or the file is cut short)");
      }
    }
  }

  static int type_size(const std::string& t) {
    if (t == "char" || t == "uchar" || t == "int8" || t == "uint8") return 1;
    if (t == "short" || t == "ushort" || t == "int16" || t == "uint16") return 2;
    if (t == "double" || t == "float64") return 8;
    return 4;
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
      // ASCII: the next value on the item's line (read() skips to the item's first value).
      while (pos_ < text_.size() && (text_[pos_] == ' ' || text_[pos_] == '\t')) ++pos_;
      if (pos_ < text_.size() && (text_[pos_] == '\n' || text_[pos_] == '\r'))
        fail("the line ends before the item's last value (the header declares more)");
      size_t e = pos_;
      while (e < text_.size() && e - pos_ < kMaxNumberLength && !std::isspace(static_cast<unsigned char>(text_[e]))) ++e;
      if (e == pos_) fail("file ends inside the data");
      if (e - pos_ == kMaxNumberLength)
        fail("a value of " + std::to_string(kMaxNumberLength) + " bytes or more ('" + printable(text_.substr(pos_, 20)) + "...')");
      double x = 0;
      const char* first = text_.data() + pos_;
      auto [ptr, ec] = std::from_chars(first, text_.data() + e, x);
      if (ec != std::errc() || ptr != text_.data() + e)
        fail("expected a number, found '" + printable(text_.substr(pos_, std::min<size_t>(e - pos_, 40))) + "'");
      pos_ = e;
      return x;
    }
    auto take = [&](auto v) {
      if (pos_ + sizeof(v) > text_.size()) fail("file ends inside the binary data");
      unsigned char bytes[sizeof(v)];
      std::memcpy(bytes, text_.data() + pos_, sizeof(v));
      if (swap_bytes_) std::reverse(bytes, bytes + sizeof(v));
      std::memcpy(&v, bytes, sizeof(v));
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

  // ASCII: skips white space, counting line breaks (LF, CR LF and CR).
  void skip_space() {
    for (; pos_ < text_.size() && std::isspace(static_cast<unsigned char>(text_[pos_])); ++pos_)
      line_ += text_[pos_] == '\n' || (text_[pos_] == '\r' && text_.substr(pos_ + 1, 1) != "\n");
  }

  // ASCII: an item is one line; a value left on it means the header and the data disagree.
  void end_item(const Element& e, long i) {
    if (binary_) return;
    while (pos_ < text_.size() && (text_[pos_] == ' ' || text_[pos_] == '\t')) ++pos_;
    if (pos_ < text_.size() && text_[pos_] != '\n' && text_[pos_] != '\r') {
      const std::string_view rest = text_.substr(pos_, text_.find_first_of("\r\n", pos_) - pos_);
      fail(e.name + " " + std::to_string(i) + " has more values than the header's " + std::to_string(e.props.size()) +
           " properties ('" + printable(rest.substr(0, 20)) + "')");
    }
  }

  static std::string number(double x) {  // whole numbers up to 1e15 in full (4294967295, not 4.29497e+09)
    char text[32];
    std::snprintf(text, sizeof text, "%.15g", x);
    return text;
  }

  std::string_view text_;
  std::string path_, who_;
  std::string property_;  // a vertex property read() keeps the values of
  size_t pos_ = 0;
  int line_ = 0;
  bool binary_ = false;
  bool swap_bytes_ = false;  // binary_big_endian
  bool in_header_ = true;
  int first_unread_line_ = 0;  // header line of the first property read past (a colour, a normal), or 0
  bool vertices_read_ = false;  // the vertex element is read (it came before the one being read)
  std::vector<Element> elements_;
};

// STL keeps no vertex list: corners with the same coordinates are one vertex, numbered in the order they
// first appear (as OpenMesh's reader numbers them). Our own reader because OpenMesh's detaches faces it
// cannot add to a manifold mesh, giving them copies of their vertices.
class StlVertices {
 public:
  int index(Vec3 p) {
    p.array() += 0.0;  // -0 and +0 are one coordinate
    const auto [it, added] = ids_.try_emplace(Key{p[0], p[1], p[2]}, static_cast<int>(points.size()));
    if (added) points.push_back(p);
    return it->second;
  }
  std::vector<Vec3> points;

 private:
  using Key = std::array<double, 3>;
  struct Hash {
    size_t operator()(const Key& k) const {
      size_t h = 0;
      for (double x : k) {
        std::uint64_t bits;
        std::memcpy(&bits, &x, sizeof(bits));
        h = (h ^ bits) * 0x100000001b3ull + (h >> 29);
      }
      return h;
    }
  };
  std::unordered_map<Key, int, Hash> ids_;
};

FileContents read_stl(std::string_view text, const std::string& path, const std::string& who) {
  FileContents soup;
  StlVertices vertices;
  std::uint32_t count = 0;
  if (text.size() >= 84) std::memcpy(&count, text.data() + 80, 4);
  const bool binary = text.size() >= 84 && text.size() == 84 + 50ull * count;
  // ASCII STL holds no NUL byte; a binary header that starts with "solid" usually does.
  const bool has_nul = text.substr(0, 1024).find('\0') != std::string_view::npos;
  if (binary) {  // even when its 80-byte header starts with "solid", as some writers do
    for (std::uint32_t t = 0; t < count; ++t) {
      float xyz[12];  // normal, then three corners
      std::memcpy(xyz, text.data() + 84 + 50ull * t, sizeof(xyz));
      for (int k = 1; k <= 3; ++k) {
        const Vec3 p(xyz[3 * k], xyz[3 * k + 1], xyz[3 * k + 2]);
        if (!p.allFinite())
          throw InvalidInput(who + ": " + path + ": triangle " + std::to_string(t) +
                             " has a non-finite coordinate");
        soup.corners.push_back(vertices.index(p));
      }
      soup.offsets.push_back(static_cast<int>(soup.corners.size()));
      soup.lines.push_back(0);
    }
  } else if (text.substr(0, 5) == "solid" && !has_nul) {
    // ASCII: solid / facet normal / outer loop / vertex x y z ... / endloop / endfacet / endsolid.
    LineReader reader(text, path, who);
    std::string_view line;
    int loop_corners = -1;  // -1 outside a loop
    while (reader.next(line)) {
      const std::string_view key = next_token(line);
      if (key == "vertex") {
        if (loop_corners < 0) reader.fail("'vertex' outside an 'outer loop'");
        soup.corners.push_back(vertices.index(parse_point(line, reader)));
        ++loop_corners;
      } else if (key == "outer") {
        loop_corners = 0;
      } else if (key == "endloop") {
        if (loop_corners < 3)
          reader.fail("facet has " + std::to_string(std::max(loop_corners, 0)) +
                      " corners (at least 3 needed)");
        soup.offsets.push_back(static_cast<int>(soup.corners.size()));
        soup.lines.push_back(reader.number());
        loop_corners = -1;
      } else if (key != "solid" && key != "facet" && key != "endfacet" && key != "endsolid") {
        reader.fail("expected an ASCII STL keyword, found '" + std::string(key.substr(0, 40)) + "'");
      }
    }
    if (loop_corners >= 0) reader.fail("file ends inside a facet");
  } else if (text.size() < 84) {
    throw InvalidInput(who + ": " + path + " is too short to be a binary STL file");
  } else {
    throw InvalidInput(who + ": " + path + " is not an STL file (binary size " + std::to_string(text.size()) +
                       " bytes does not match its " + std::to_string(count) + " triangles (" +
                       std::to_string(84 + 50ull * count) + " bytes), and it is not ASCII STL)");
  }
  if (soup.offsets.size() == 1)
    throw InvalidInput(who + ": " + path + " has no triangles (an STL file is a list of triangles)");
  soup.points = std::move(vertices.points);
  return soup;
}

FileContents read_contents(const std::string& path, const std::string& who) {
  const std::string ext = file_extension(path);
  check_mesh_format(path, who);
  const FileText file(path, who.c_str());
  const std::string_view text = file.text();
  if (ext == ".off") return read_off(text, path, who);
  if (ext == ".obj") return read_obj(text, path, who);
  if (ext == ".ply") return PlyReader(text, path, who).read();
  return read_stl(text, path, who);
}

// Splits polygon corner[0 .. n) (n > 3) of `points` into n − 2 triangles that turn the polygon's way (their
// normals along its Newell normal), judged by their shape: twice the area in the plane of that normal over
// the longest edge squared in space (0.87 for an equilateral triangle in the plane; 0 on a line, and small
// for a triangle standing steeply on that plane). Of the splits that keep the polygon as drawn:
// - the fan from its first corner where it is shaped nearly as well as the best split (half as well; a
//   quad's a tenth: the split every mesh tool reads);
// - else the best-shaped split, whose worst triangle is the largest (dynamic programming over the
//   polygon's diagonals, up to kOptimalCorners corners): a polygon with a corner of nearly 180° (an edge
//   split to mend a T-junction, two quads merged) gave a sliver along its neighbour's edges from its first
//   corner, and the two polygons on either side of one such chain the same sliver twice (a non-manifold
//   edge, or self-intersections on a curved mesh); two polygons sharing a chain raised like a roof each
//   closed the chain with a chord, standing steeply on its plane, over the same lens; a square whose sides
//   carry corners bulged by 1e-9 had a sliver in every fan and was refused by the shell as singular.
// Larger polygons take the best-shaped fan (up to kShapedFans corners; the first corner's beyond), or
// where no fan keeps the polygon as drawn (concave), ear clipping. A polygon whose corners lie on a line
// keeps its fan (its triangles are degenerate, which check_surface reports).
enum class PolygonSplit { Fan, Other, CrossesItself };
constexpr int kOptimalCorners = 256, kShapedFans = 1024;
// shared (null: none): per corner, up to two other polygons with a side at it. A triangle whose three
// corners all touch one other polygon lies on a chain of sides the two share, and is refused: two polygons
// sharing a chain raised like a roof both closed it with the same chord (the same triangles twice: an edge
// in 3 or 4 faces). Where that leaves no split, the polygon is split without it.
PolygonSplit split_polygon(const std::vector<Vec3>& points, const int* corner, int n,
                           std::vector<std::array<int, 3>>& out,
                           const std::vector<std::array<int, 2>>* shared = nullptr) {
  // The corners relative to the first, over the polygon's extent: the Newell normal's products neither
  // underflow (a concave pentagon 1e-100 across had no normal and was fanned, folded) nor overflow (1e80
  // across: refused as crossing itself), nor cancel far from the origin.
  double extent = 0;
  for (int k = 1; k < n; ++k)
    extent = std::max(extent, (points[corner[k]] - points[corner[0]]).cwiseAbs().maxCoeff());
  std::vector<Vec3> x(n, Vec3::Zero());
  if (extent > 0)
    for (int k = 1; k < n; ++k) x[k] = (points[corner[k]] - points[corner[0]]) / extent;
  Vec3 normal = Vec3::Zero();  // Newell: twice the vector area, whatever the first corner
  for (int k = 0; k < n; ++k) normal += x[k].cross(x[(k + 1) % n]);
  if (!(normal.squaredNorm() > 0)) {  // no area: all corners on a line, or lobes that cancel (a bow tie)
    for (int k = 1; k + 1 < n; ++k)
      if (x[k].cross(x[k + 1]).squaredNorm() > 0) return PolygonSplit::CrossesItself;
    for (int k = 1; k + 1 < n; ++k) out.push_back({corner[0], corner[k], corner[k + 1]});
    return PolygonSplit::Fan;
  }
  // The plane (u, v) with u × v along the normal, so the polygon runs counter-clockwise.
  const Vec3 u = normal.unitOrthogonal(), v = normal.normalized().cross(u);
  std::vector<Eigen::Vector2d> q(n);
  for (int k = 0; k < n; ++k) q[k] = {x[k].dot(u), x[k].dot(v)};
  const auto turn = [&](int a, int b, int c) {  // > 0: a, b, c counter-clockwise
    const Eigen::Vector2d e = q[b] - q[a], f = q[c] - q[a];
    return e.x() * f.y() - e.y() * f.x();
  };
  const auto on_shared_chain = [&](int a, int b, int c) {
    for (const int other : (*shared)[a])
      if (other >= 0 && ((*shared)[b][0] == other || (*shared)[b][1] == other) &&
          ((*shared)[c][0] == other || (*shared)[c][1] == other))
        return true;
    return false;
  };
  const auto shape = [&](int a, int b, int c) {  // ≤ 0 where turned over or flat (or refused)
    if (shared && on_shared_chain(a, b, c)) return 0.0;
    const Vec3 &pa = x[a], &pb = x[b], &pc = x[c];
    const double longest =
        std::max({(pb - pa).squaredNorm(), (pc - pb).squaredNorm(), (pa - pc).squaredNorm()});
    const double t = turn(a, b, c);
    return t > 0 ? t / longest : 0.0;
  };
  const auto fan_shape = [&](int apex) {  // the worst triangle of the fan from corner apex (0: no fan)
    double worst = 1;
    for (int k = 1; k + 1 < n && worst > 0; ++k)
      worst = std::min(worst, shape(apex, (apex + k) % n, (apex + k + 1) % n));
    return worst;
  };
  const auto fan = [&](int apex) {
    for (int k = 1; k + 1 < n; ++k)
      out.push_back({corner[apex], corner[(apex + k) % n], corner[(apex + k + 1) % n]});
    return apex == 0 ? PolygonSplit::Fan : PolygonSplit::Other;
  };
  const double first = fan_shape(0);
  // A flat convex polygon whose first fan has no sliver keeps it without the search (a mesh of 1000 circles
  // of 100 corners loaded in 4.5 s with it, 0.1 s without): every other split is as flat, and none is
  // needed to avoid a sliver.
  bool convex = true, flat = true;
  const Vec3 axis = normal.normalized();
  for (int k = 0; k < n && (convex || flat); ++k) {
    convex = convex && turn((k + n - 1) % n, k, (k + 1) % n) > 0;
    flat = flat && std::abs(x[k].dot(axis)) <= 1e-3;  // of the extent, which is 1 here
  }
  if (convex && flat && first >= 1e-2) return fan(0);
  if (n <= kOptimalCorners) {
    // best[i][j]: the largest worst-triangle shape of a split of the sub-polygon i, i+1, ..., j closed by
    // the diagonal (i, j); 0 where there is none. A diagonal joins two corners through the polygon's inside:
    // it leaves each end into the corner's interior and crosses or touches no edge.
    const auto inside = [&](int i, int j) {  // (i, j) leaves corner i into its interior
      const int before = (i + n - 1) % n, after = (i + 1) % n;
      return turn(before, i, after) > 0 ? turn(i, j, before) > 0 && turn(j, i, after) > 0
                                        : !(turn(i, j, after) >= 0 && turn(j, i, before) >= 0);
    };
    const auto between = [&](int i, int j, int k) {  // k, on the line of (i, j), lies on the segment
      return (q[k] - q[i]).dot(q[j] - q[i]) >= 0 && (q[k] - q[j]).dot(q[i] - q[j]) >= 0;
    };
    const auto crosses = [&](int i, int j) {  // (i, j) meets an edge other than those at i and j
      for (int k = 0; k < n; ++k) {
        const int l = (k + 1) % n;
        if (k == i || k == j || l == i || l == j) continue;
        const double a = turn(i, j, k), b = turn(i, j, l), c = turn(k, l, i), d = turn(k, l, j);
        if (a != 0 && b != 0 && (a > 0) != (b > 0) && (c >= 0) != (d >= 0)) return true;
        if ((a == 0 && between(i, j, k)) || (b == 0 && between(i, j, l))) return true;  // a corner on it
      }
      return false;
    };
    std::vector<double> best(n * n, 0);
    std::vector<int> split(n * n, -1);
    std::vector<char> usable(n * n, 0);  // an edge of the polygon or a diagonal
    for (int i = 0; i < n; ++i)
      for (int j = i + 1; j < n; ++j)
        usable[i * n + j] = convex || j == i + 1 || (i == 0 && j == n - 1) ||
                            (inside(i, j) && inside(j, i) && !crosses(i, j));
    for (int i = 0; i + 1 < n; ++i) best[i * n + i + 1] = 1;  // an edge: nothing to split
    for (int length = 2; length < n; ++length)
      for (int i = 0; i + length < n; ++i) {
        const int j = i + length;
        if (!usable[i * n + j]) continue;
        for (int k = i + 1; k < j; ++k) {
          const double s = std::min({best[i * n + k], best[k * n + j], shape(i, k, j)});
          if (s > best[i * n + j]) best[i * n + j] = s, split[i * n + j] = k;
        }
      }
    const double optimum = best[n - 1];  // (0, n − 1) is the polygon's closing edge
    if (first > 0 && first >= (n == 4 ? 0.1 : 0.5) * optimum) return fan(0);
    std::vector<std::pair<int, int>> stack;
    if (optimum > 0) stack.push_back({0, n - 1});  // else rounding refused every split: ear clipping below
    while (!stack.empty()) {
      const auto [i, j] = stack.back();
      stack.pop_back();
      if (j - i < 2) continue;
      const int k = split[i * n + j];
      out.push_back({corner[i], corner[k], corner[j]});
      stack.push_back({i, k}), stack.push_back({k, j});
    }
    if (optimum > 0) return PolygonSplit::Other;
  }
  double best = first;
  int apex = 0;
  for (int k = 1; k < n && n <= kShapedFans; ++k)
    if (const double s = fan_shape(k); s > best) best = s, apex = k;
  if (first > 0 && first >= 0.5 * best) apex = 0;
  if (best > 0) return fan(apex);
  // Ear clipping: the first ear from the polygon's start each time.
  std::vector<int> left(n);
  std::iota(left.begin(), left.end(), 0);
  const size_t start = out.size();
  while (left.size() > 3) {
    const int m = static_cast<int>(left.size());
    int ear = -1;
    for (int i = 0; i < m && ear < 0; ++i) {
      const int a = left[(i + m - 1) % m], b = left[i], c = left[(i + 1) % m];
      if (!(turn(a, b, c) > 0)) continue;  // a reflex or straight corner is no ear
      bool empty = true;                   // no other corner inside or on the ear
      for (int j : left)
        if (j != a && j != b && j != c && q[j] != q[a] && q[j] != q[b] && q[j] != q[c] &&
            turn(a, b, j) >= 0 && turn(b, c, j) >= 0 && turn(c, a, j) >= 0)
          empty = false;
      if (empty) ear = i;
    }
    if (ear < 0) {
      out.resize(start);
      return shared ? split_polygon(points, corner, n, out) : PolygonSplit::CrossesItself;
    }
    out.push_back({corner[left[(ear + m - 1) % m]], corner[left[ear]], corner[left[(ear + 1) % m]]});
    left.erase(left.begin() + ear);
  }
  if (!(turn(left[0], left[1], left[2]) > 0)) {
    out.resize(start);
    return shared ? split_polygon(points, corner, n, out) : PolygonSplit::CrossesItself;
  }
  out.push_back({corner[left[0]], corner[left[1]], corner[left[2]]});
  return PolygonSplit::Other;
}

// The file's vertices as they are; its polygons as triangles (split_polygon), without faces that repeat a
// vertex index or the vertex set of an earlier triangle.
TriangleSoup triangulate(const FileContents& soup, const std::string& path, const std::string& who,
                         LoadReport& report) {
  const int nv = static_cast<int>(soup.points.size());
  const int npoly = static_cast<int>(soup.offsets.size()) - 1;
  if (nv == 0) throw InvalidInput(who + ": " + path + " has no vertices");
  report.first_ignored_line = soup.first_ignored_line;
  report.first_attribute_line = soup.first_attribute_line;
  TriangleSoup out;
  out.P.resize(nv, 3);
  for (int i = 0; i < nv; ++i) out.P.row(i) = soup.points[i];
  std::vector<std::array<int, 3>> triangles;
  triangles.reserve(soup.corners.size() > 2 * static_cast<size_t>(npoly) ? soup.corners.size() - 2 * npoly
                                                                         : 0);
  // The sides of the polygons (more than 3 corners), to find the ones two of them share (split_polygon).
  std::vector<std::pair<std::uint64_t, int>> sides;
  for (int f = 0; f < npoly; ++f)
    if (const int n = soup.offsets[f + 1] - soup.offsets[f]; n > 3)
      for (int k = 0; k < n; ++k) {
        const int* corner = soup.corners.data() + soup.offsets[f];
        const auto [a, b] = std::minmax(corner[k], corner[(k + 1) % n]);
        sides.push_back({std::uint64_t(std::uint32_t(a)) << 32 | std::uint32_t(b), f});
      }
  std::sort(sides.begin(), sides.end());
  std::vector<std::array<int, 2>> shared;
  std::vector<int> polygon, sorted;
  for (int f = 0; f < npoly; ++f) {
    const int* listed = soup.corners.data() + soup.offsets[f];
    const int listed_n = soup.offsets[f + 1] - soup.offsets[f];
    for (int k = 0; k < listed_n; ++k)
      if (listed[k] < 0 || listed[k] >= nv)
        throw InvalidInput(who + ": " + path +
                           (soup.lines[f] > 0 ? " line " + std::to_string(soup.lines[f]) : "") + ": face " +
                           std::to_string(f) + " has vertex index " + std::to_string(listed[k]) +
                           " out of range [0, " + std::to_string(nv) + ")");
    // A corner listed twice in a row (`4 a b c c`, or first and last) is a side of no length: left out, the
    // polygon keeps its shape (dropping the whole face left a hole).
    polygon.clear();
    for (int k = 0; k < listed_n; ++k)
      if (listed[k] != listed[(k + 1) % listed_n]) polygon.push_back(listed[k]);
    const int* corner = polygon.data();
    const int n = static_cast<int>(polygon.size());
    sorted = polygon;
    std::sort(sorted.begin(), sorted.end());
    if (n < 3 || std::adjacent_find(sorted.begin(), sorted.end()) != sorted.end()) {
      ++report.degenerate_faces_skipped;
      continue;
    }
    report.repeated_corners_merged += n < listed_n;
    if (n == 3) {
      triangles.push_back({corner[0], corner[1], corner[2]});
      continue;
    }
    ++report.polygons_triangulated;
    for (int k = 0; k < n; ++k)  // a zero-length side leaves no split without a flat triangle
      if (soup.points[corner[k]] == soup.points[corner[(k + 1) % n]])
        throw InvalidInput(who + ": " + path +
                           (soup.lines[f] > 0 ? " line " + std::to_string(soup.lines[f]) : "") + ": face " +
                           std::to_string(f) + " is a polygon whose corners " + std::to_string(k) + " and " +
                           std::to_string((k + 1) % n) + " (vertices " + std::to_string(corner[k]) + " and " +
                           std::to_string(corner[(k + 1) % n]) +
                           ") are at the same point: merge the two vertices or drop one from the face");
    // Per corner, the other polygons with a side at it (the one after it, then the one before).
    shared.assign(static_cast<size_t>(n), {-1, -1});
    bool shares = false;
    for (int k = 0; k < n; ++k) {
      const auto [a, b] = std::minmax(corner[k], corner[(k + 1) % n]);
      const std::uint64_t key = std::uint64_t(std::uint32_t(a)) << 32 | std::uint32_t(b);
      for (auto it = std::lower_bound(sides.begin(), sides.end(), std::pair{key, -1});
           it != sides.end() && it->first == key; ++it)
        if (it->second != f) {
          shared[k][0] = shared[(k + 1) % n][1] = it->second;
          shares = true;
        }
    }
    const PolygonSplit split = split_polygon(soup.points, corner, n, triangles, shares ? &shared : nullptr);
    if (split == PolygonSplit::CrossesItself)
      throw InvalidInput(who + ": " + path +
                         (soup.lines[f] > 0 ? " line " + std::to_string(soup.lines[f]) : "") + ": face " +
                         std::to_string(f) + " is a polygon of " + std::to_string(n) +
                         " corners that crosses itself (in the plane of its normal): no split into triangles "
                         "keeps it as drawn; split it into triangles or simple polygons in the modeller");
    report.polygons_split_otherwise += split == PolygonSplit::Other;
  }
  // Duplicates: sort the vertex sets, keep the first triangle of each.
  std::vector<std::array<int, 4>> keys(triangles.size());
  for (size_t t = 0; t < triangles.size(); ++t) {
    keys[t] = {triangles[t][0], triangles[t][1], triangles[t][2], static_cast<int>(t)};
    std::sort(keys[t].begin(), keys[t].begin() + 3);
  }
  std::sort(keys.begin(), keys.end());
  std::vector<char> keep(triangles.size(), 1);
  for (size_t i = 1; i < keys.size(); ++i)
    if (std::equal(keys[i].begin(), keys[i].begin() + 3, keys[i - 1].begin())) {
      keep[keys[i][3]] = 0;
      ++report.duplicate_faces_dropped;
    }
  out.F.resize(static_cast<Eigen::Index>(triangles.size()) - report.duplicate_faces_dropped, 3);
  for (size_t t = 0, row = 0; t < triangles.size(); ++t)
    if (keep[t]) out.F.row(row++) << triangles[t][0], triangles[t][1], triangles[t][2];
  return out;
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

Eigen::VectorXd load_vertex_property(const std::string& path, const std::string& name) {
  const std::string who = "load_vertex_property";
  if (file_extension(path) != ".ply")
    throw InvalidInput(who + ": " + path + ": per-vertex properties are read from PLY files");
  if (name.empty()) throw InvalidInput(who + ": no property name given");
  const FileText file(path, who.c_str());
  const FileContents contents = PlyReader(file.text(), path, who, name).read();
  if (contents.points.empty()) throw InvalidInput(who + ": " + path + " has no vertices");
  return Eigen::Map<const Eigen::VectorXd>(contents.vertex_property.data(),
                                           static_cast<Eigen::Index>(contents.vertex_property.size()));
}

std::string file_extension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext;
}

void check_mesh_format(const std::string& path, const std::string& who) {
  std::error_code error;
  if (std::filesystem::is_directory(path, error))  // a folder has no format to name
    throw InvalidInput(who + ": " + path + " is a folder; give a mesh file name (.off .obj .ply .stl) in it");
  const std::string ext = file_extension(path);
  if (ext != ".off" && ext != ".obj" && ext != ".ply" && ext != ".stl")
    throw InvalidInput(who + ": " + path + ": unknown format '" + ext + "' (supported: .off .obj .ply .stl)");
}

std::string faces_changed_on_load(const LoadReport& r) {
  std::string text;
  const auto add = [&](int n, const char* one, const char* many, const char* what) {
    if (n > 0)
      text += (text.empty() ? "" : ", ") + std::to_string(n) + " " + (n == 1 ? one : many) + " " + what;
  };
  add(r.duplicate_faces_dropped, "duplicate face", "duplicate faces", "dropped");
  add(r.degenerate_faces_skipped, "face repeating a vertex", "faces repeating a vertex", "dropped");
  add(r.repeated_corners_merged, "face listing a corner twice in a row",
      "faces listing a corner twice in a row", "read without the repetition");
  add(r.polygons_triangulated, "polygon", "polygons", "triangulated");
  add(r.faces_flipped, "face", "faces", "turned over to agree with their neighbours");
  return text;
}

TriangleSoup load_soup(const std::string& path, LoadReport* report) {
  LoadReport local;
  LoadReport& r = report ? *report : local;
  r = LoadReport{};
  return triangulate(read_contents(path, "load_soup"), path, "load_soup", r);
}

Mesh load_mesh(const std::string& path, LoadReport* report) {
  LoadReport local;
  LoadReport& r = report ? *report : local;
  r = LoadReport{};
  TriangleSoup soup = triangulate(read_contents(path, "load_mesh"), path, "load_mesh", r);
  const std::string space_methods = "space methods (lattice, cage-mvc, cage-harmonic, rbf) deform such input";
  if (soup.F.rows() == 0 && r.degenerate_faces_skipped > 0)
    throw InvalidInput("load_mesh: " + path + " has no valid faces (all " +
                       std::to_string(r.degenerate_faces_skipped) + " repeat a vertex index)");
  if (soup.F.rows() == 0)
    throw InvalidInput("load_mesh: " + path + " has no faces (a point cloud is not a mesh; " + space_methods +
                       ")");
  const SurfaceCheck check = check_surface(soup.P, soup.F);
  r.faces_flipped = check.flipped_faces;
  if (!check.is_manifold_mesh())
    throw TopologyError("load_mesh: " + path + " is not a manifold triangle mesh: " + check.problem() + "; " +
                        space_methods);
  Mesh mesh;
  const int nv = static_cast<int>(soup.P.rows()), nf = static_cast<int>(soup.F.rows());
  mesh.reserve(nv, 3 * nf, nf);
  for (int i = 0; i < nv; ++i) mesh.add_vertex(Mesh::Point(soup.P(i, 0), soup.P(i, 1), soup.P(i, 2)));
  for (int f = 0; f < nf; ++f) {
    const int a = soup.F(f, 0), b = soup.F(f, 1), c = soup.F(f, 2);
    omerr().disable();
    const bool added =
        mesh.add_face(mesh.vertex_handle(a), mesh.vertex_handle(b), mesh.vertex_handle(c)).is_valid();
    omerr().enable();
    // check_surface found the faces manifold and oriented them, so OpenMesh should take every one.
    if (!added)
      throw TopologyError("load_mesh: " + path + ": OpenMesh refused face " + std::to_string(f) + " (" +
                          std::to_string(a) + ", " + std::to_string(b) + ", " + std::to_string(c) +
                          ") of a surface found manifold; " + space_methods);
  }
  return mesh;
}

void save_mesh(const Positions& P, const Faces& F, const std::string& path, const SaveOptions& options) {
  const std::string ext = file_extension(path);
  check_mesh_format(path, "save_mesh");
  // The first vertex whose row (of P, or of the scalars) holds NaN or inf.
  const auto first_non_finite = [](const auto& rows) {
    Eigen::Index v = 0;
    while (v < rows.rows() && rows.row(v).allFinite()) ++v;
    return std::to_string(v);
  };
  if (!P.allFinite())
    throw InvalidInput("save_mesh: " + path + ": positions contain NaN or inf (the first at vertex " +
                       first_non_finite(P) + "); nothing written");
  if (options.vertex_scalar) {
    if (ext != ".ply") throw InvalidInput("save_mesh: " + path + ": per-vertex scalars need the .ply format");
    if (options.vertex_scalar->size() != P.rows())
      throw InvalidInput("save_mesh: " + path + ": " + std::to_string(options.vertex_scalar->size()) +
                         " scalars for " + std::to_string(P.rows()) + " vertices");
    // Readers take NaN in a PLY property differently (or not at all): refused as positions are.
    if (!options.vertex_scalar->allFinite())
      throw InvalidInput("save_mesh: " + path + ": the scalar is NaN or inf at vertex " +
                         first_non_finite(*options.vertex_scalar) + "; nothing written");
    const std::string& name = options.scalar_name;  // a PLY word, and not a coordinate's name
    if (name.empty() || name == "x" || name == "y" || name == "z" ||
        std::any_of(name.begin(), name.end(),
                    [](char c) { return !std::isgraph(static_cast<unsigned char>(c)); }))
      throw InvalidInput("save_mesh: " + path + ": the scalar's property name '" +
                         printable(name.substr(0, 40)) +
                         "' must be one word of visible characters other than x, y and z; nothing written");
  }
  const long nv = P.rows(), nf = F.rows();
  std::string out;
  out.reserve(static_cast<size_t>(nv) * 64 + static_cast<size_t>(nf) * 32 + 256);
  if (ext == ".stl") {
    // STL has no vertex list: a point cloud would come back as nothing.
    if (nf == 0)
      throw InvalidInput("save_mesh: " + path +
                         ": STL stores triangles only and there are none (a point cloud): "
                         "use .ply, .off or .obj; nothing written");
    // Binary STL holds single precision: a coordinate beyond its range would be written as inf, and a mesh
    // whose coordinates all lie below its normal range (1.2e-38) and float's 7 digits above it would lose
    // its digits or collapse to a point (a tetrahedron 1e-50 across came back as one vertex).
    constexpr double kSmallest = static_cast<double>(std::numeric_limits<float>::min()) /
                                 std::numeric_limits<float>::epsilon();  // about 1e-31
    if (const double largest = nv > 0 ? P.cwiseAbs().maxCoeff() : 0.0; largest > 0 && largest < kSmallest)
      throw InvalidInput(
          "save_mesh: " + path + ": the largest coordinate is " + format_number(largest) +
          ", too small for the single precision STL stores (its digits need 1e-31 or more): use "
          ".ply, .off or .obj; nothing written");
    // And STL has no vertex list: a reader joins equal corners, so vertices that single precision rounds
    // to one point become one (the lift moved 1e6 away came back with 475 of its 9409 vertices).
    {
      std::vector<std::pair<std::array<float, 3>, long>> rounded(static_cast<size_t>(nv));
      for (long i = 0; i < nv; ++i)
        rounded[i] = {{static_cast<float>(P(i, 0)), static_cast<float>(P(i, 1)), static_cast<float>(P(i, 2))},
                      i};
      std::sort(rounded.begin(), rounded.end());
      for (size_t k = 1; k < rounded.size(); ++k)
        if (rounded[k].first == rounded[k - 1].first &&
            P.row(rounded[k].second) != P.row(rounded[k - 1].second))
          throw InvalidInput(
              "save_mesh: " + path + ": vertices " + std::to_string(rounded[k - 1].second) + " and " +
              std::to_string(rounded[k].second) +
              " round to one point in the single precision STL stores (edges too short for "
              "coordinates of " +
              format_number(P.cwiseAbs().maxCoeff()) +
              ": move the mesh nearer the origin, or use .ply, .off or .obj); nothing written");
    }
    for (long i = 0; i < nv; ++i)
      if (!(P.row(i).cwiseAbs().maxCoeff() <= std::numeric_limits<float>::max()))
        throw InvalidInput(
            "save_mesh: " + path + ": vertex " + std::to_string(i) + " has a coordinate of " +
            format_number(P.row(i).cwiseAbs().maxCoeff()) +
            ", beyond the single precision STL stores (3.4e38): use .ply, .off or .obj; nothing "
            "written");
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

StlReadBack stl_read_back(const Positions& P, const Faces& F) {
  const long nv = P.rows();
  StlReadBack out;
  std::vector<long> first_use;  // vertices in the order faces first use them
  std::vector<char> used(static_cast<size_t>(nv), 0);
  for (Eigen::Index f = 0; f < F.rows(); ++f)
    for (int k = 0; k < 3; ++k) {
      const int v = F(f, k);
      if (v < 0 || v >= nv)
        throw InvalidInput("stl_read_back: face " + std::to_string(f) + " has vertex index " +
                           std::to_string(v) + " out of range [0, " + std::to_string(nv) + ")");
      if (!used[v]) used[v] = 1, first_use.push_back(v);
    }
  out.unused = static_cast<int>(nv - static_cast<long>(first_use.size()));
  // Equal points (+0 and -0 alike, as the reader joins them) among the used vertices.
  std::vector<std::pair<std::array<double, 3>, long>> points(first_use.size());
  for (size_t k = 0; k < first_use.size(); ++k) {
    const long v = first_use[k];
    points[k] = {{P(v, 0) + 0.0, P(v, 1) + 0.0, P(v, 2) + 0.0}, v};
  }
  std::sort(points.begin(), points.end());
  for (size_t k = 1; k < points.size(); ++k) out.merged += points[k].first == points[k - 1].first;
  out.vertices = static_cast<int>(first_use.size()) - out.merged;
  out.renumbered = out.unused > 0 || out.merged > 0;
  for (size_t k = 0; k < first_use.size() && !out.renumbered; ++k)
    out.renumbered = first_use[k] != static_cast<long>(k);
  return out;
}

}  // namespace msd
