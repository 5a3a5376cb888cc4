#include "apps/msdeform/region_options.h"

#include <cstdio>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <utility>

#include "apps/msdeform/commands.h"
#include "msdeform/core/adjacency.h"
#include "msdeform/core/errors.h"
#include "msdeform/core/extent.h"
#include "msdeform/core/mesh_io.h"
#include "msdeform/core/rotation.h"

namespace msd::cli {
namespace {

constexpr double kPi = 3.14159265358979323846;

// "a,b,c" as finite numbers, as many as one of `counts`. `where` (the option and its value) and `what`
// (the expected form) name them in errors.
std::vector<double> numbers(const std::string& where, const std::string& text, std::vector<int> counts,
                            const std::string& what) {
  std::vector<double> out;
  size_t at = 0;
  while (true) {
    const size_t comma = text.find(',', at);
    const std::string item = text.substr(at, comma == std::string::npos ? std::string::npos : comma - at);
    const std::optional<double> x = cli::decimal_number(item);
    if (!x) throw InvalidInput(where + ": '" + item + "' is not a finite decimal number (expected " + what + ")");
    out.push_back(*x);
    if (comma == std::string::npos) break;
    at = comma + 1;
  }
  for (int c : counts)
    if (static_cast<int>(out.size()) == c) return out;
  throw InvalidInput(where + ": " + std::to_string(out.size()) + " numbers given, expected " + what);
}

int integer(const std::string& where, double x, const char* what, long lo, long hi) {
  if (x != std::floor(x) || x < lo || x > hi) {
    char got[32];
    std::snprintf(got, sizeof got, "%.17g", x);
    throw InvalidInput(where + ": " + what + " must be an integer in [" + std::to_string(lo) + ", " +
                       std::to_string(hi) + "], got " + got);
  }
  return static_cast<int>(x);
}

Vec3 vec(const std::vector<double>& v, size_t at = 0) { return Vec3(v[at], v[at + 1], v[at + 2]); }

// The vertices a --fixed or --handle SPEC selects (see region_options.h).
std::vector<int> select(const std::string& option, const std::string& spec, const Positions& P, const Faces& F,
                        bool handle) {
  const size_t colon = spec.find(':');
  const std::string kind = spec.substr(0, colon), args = colon == std::string::npos ? "" : spec.substr(colon + 1);
  const int nv = static_cast<int>(P.rows());
  const std::string where = option + " " + spec;
  if (kind == "box") {
    const auto v = numbers(where, args, {6}, "XMIN,YMIN,ZMIN,XMAX,YMAX,ZMAX");
    try {
      return select_box(P, vec(v), vec(v, 3));
    } catch (const InvalidInput& e) {  // corners the wrong way round: said with the option, not the function
      const std::string what = e.what(), prefix = "select_box: ";
      throw InvalidInput(where + ": " + (what.rfind(prefix, 0) == 0 ? what.substr(prefix.size()) : what));
    }
  }
  if (kind == "sphere") {
    const auto v = numbers(where, args, {4}, "X,Y,Z,R");
    if (v[3] < 0) throw InvalidInput(where + ": the radius is negative");
    return select_sphere(P, vec(v), v[3]);
  }
  if (kind == "halfspace") {
    const auto v = numbers(where, args, {4}, "NX,NY,NZ,D: the vertices with n·p < d");
    const Vec3 n = vec(v);
    if (n.squaredNorm() == 0) throw InvalidInput(where + ": the normal is zero");
    std::vector<int> out;
    for (int i = 0; i < nv; ++i)
      if (n.dot(P.row(i).transpose()) < v[3]) out.push_back(i);
    return out;
  }
  if (kind == "vertex") {
    const auto v = numbers(where, args, {2}, "ID,RINGS");
    const int id = integer(where, v[0], "the vertex id", 0, nv - 1);
    const int rings = integer(where, v[1], "the number of rings", 0, 1000000);
    return grow_rings(F, nv, {id}, rings);
  }
  if (kind == "file") {
    const size_t comma = args.rfind(',');
    std::string path = args;
    bool by_value = false;
    long value = 0;
    if (comma != std::string::npos) {  // file:PATH,VALUE (a path may hold commas: only a number counts)
      char* end = nullptr;
      const std::string tail = args.substr(comma + 1), head = args.substr(0, comma);
      const long x = std::strtol(tail.c_str(), &end, 10);
      if (!tail.empty() && *end == '\0')
        path = head, value = x, by_value = true;
      else if (!std::filesystem::exists(args) && std::filesystem::exists(head))
        throw InvalidInput(where + ": the value after the file, '" + tail + "', is not an integer (a .sel code or "
                           "a .dmat group)");
    }
    if (path.empty()) throw InvalidInput(where + ": no file given (file:PATH or file:PATH,VALUE)");
    const bool dmat = file_extension(path) == ".dmat";
    if (dmat && !by_value)
      throw InvalidInput(where + ": a .dmat file holds groups, not fixed and handle vertices: give the group, e.g. "
                         "file:" + path + ",0");
    Region r;
    try {
      r = dmat ? read_dmat_groups(path, nv) : read_sel(path, nv);
    } catch (const InvalidInput& e) {
      throw InvalidInput(where + ": " + e.what());
    }
    std::vector<int> out;
    for (int i = 0; i < nv; ++i) {
      const int code = r.code(i);
      const long file_value = dmat ? (code == Region::kFree ? -1 : code - Region::kFirstHandle) : code;
      if (by_value ? file_value == value : handle ? code >= Region::kFirstHandle : code == Region::kFixed)
        out.push_back(i);
    }
    return out;
  }
  throw InvalidInput(where + ": unknown selection '" + kind +
                     "' (box:, sphere:, halfspace:, vertex: or file:; see msdeform deform --help)");
}

}  // namespace

void RegionOptions::add_to(CLI::App& cmd, bool with_transforms) {
  auto* g = cmd.add_option_group("region", with_transforms
                                               ? "Regions and transforms without files (instead of --sel / --def)"
                                               : "Regions without files (instead of --sel)");
  group_ = g;
  auto add = [&](const char* name, std::vector<std::string>& values, const char* type, const char* help) {
    // One value per occurrence. CLI11 takes the next word even when it is an option ("--handle --translate
    // 0,0,1" would select by "--translate"): such a value is a missing one.
    const CLI::Validator not_an_option(
        [name](std::string& value) {
          return value.rfind("--", 0) == 0 ? std::string(name) + " has no value before " + value : std::string();
        },
        "");
    return g->add_option(name, values, help)
        ->type_name(type)
        ->expected(1)
        ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll)
        ->check(not_an_option);
  };
  fixed_ = add("--fixed", fixed_values_, "SPEC",
               "Fixed vertices: box:XMIN,YMIN,ZMIN,XMAX,YMAX,ZMAX | sphere:X,Y,Z,R | halfspace:NX,NY,NZ,D (n.p < d) | "
               "vertex:ID,RINGS | file:PATH[,VALUE]; repeatable, later selections win");
  handle_ = add("--handle", handle_values_, "SPEC", "The next handle, selected like --fixed; repeat for several handles");
  g->add_option("--write-sel", write_sel, "Save the region (built or loaded) as a .sel file");
  if (!with_transforms) return;
  translate_ = add("--translate", translate_values_, "X,Y,Z",
                   "Translate the handle this follows (before any --handle: every handle)");
  rotate_ = add("--rotate", rotate_values_, "AX,AY,AZ,DEG", "Rotate by DEG degrees about the axis, like --translate");
  scale_ = add("--scale", scale_values_, "S|SX,SY,SZ", "Scale, like --translate");
  about_ = add("--about", about_values_, "X,Y,Z|handle-centroid",
               "Centre of the --rotate or --scale right before it (default: the handle's centroid where the "
               "transforms before put it)");
  g->add_option("--write-def", write_def, "Save the handle transforms (built or loaded) as a .def file");
}

bool RegionOptions::builds_region() const { return fixed_ && (fixed_->count() > 0 || handle_->count() > 0); }

bool RegionOptions::builds_transforms() const {
  return translate_ &&
         (translate_->count() > 0 || rotate_->count() > 0 || scale_->count() > 0 || about_->count() > 0);
}

std::vector<std::string> RegionOptions::input_files() const {
  std::vector<std::string> files;
  for (const std::vector<std::string>* specs : {&fixed_values_, &handle_values_})
    for (const std::string& spec : *specs) {
      if (spec.rfind("file:", 0) != 0) continue;
      const std::string args = spec.substr(5);
      files.push_back(args);
      const size_t comma = args.rfind(',');
      if (comma != std::string::npos) files.push_back(args.substr(0, comma));  // file:PATH,VALUE
    }
  return files;
}

std::vector<RegionOptions::Step> RegionOptions::steps() const {
  std::vector<Step> out;
  if (!group_) return out;
  std::map<const CLI::Option*, size_t> used;
  for (const CLI::Option* o : group_->parse_order())
    if (o == fixed_ || o == handle_ || o == translate_ || o == rotate_ || o == scale_ || o == about_)
      out.push_back({o, o->results().at(used[o]++)});
  return out;
}

Region RegionOptions::build_region(const Positions& P, const Faces& F) const {
  Region region(static_cast<int>(P.rows()), Region::kFree);
  std::vector<std::string> handle_specs;
  bool any_fixed = false;
  std::string fixed_specs;
  for (const Step& s : steps()) {
    if (s.option != fixed_ && s.option != handle_) continue;
    const bool handle = s.option == handle_;
    const std::string option = (handle ? "--handle " : "--fixed ") + s.value;
    const std::vector<int> vertices = select(handle ? "--handle" : "--fixed", s.value, P, F, handle);
    if (vertices.empty())
      throw InvalidInput(option + " selects no vertex" +
                         (handle ? " (it would be handle " + std::to_string(handle_specs.size()) + ")" : std::string()));
    if (handle) {
      region.set_handle(vertices, static_cast<int>(handle_specs.size()));
      handle_specs.push_back(option);
    } else {
      region.set_fixed(vertices);
      any_fixed = true;
      fixed_specs += (fixed_specs.empty() ? "" : ", ") + option;
    }
  }
  for (size_t k = 0; k < handle_specs.size(); ++k)
    if (region.handle_vertices(static_cast<int>(k)).empty())
      throw InvalidInput(handle_specs[k] + " (handle " + std::to_string(k) +
                         ") lost all its vertices to later selections");
  if (any_fixed && region.fixed_vertices().empty())
    throw InvalidInput(fixed_specs + ": every fixed vertex was taken by a later --handle");
  return region;
}

std::vector<Mat4> RegionOptions::build_transforms(const Positions& P, const Region& region) const {
  const int nh = region.num_handles();
  std::vector<Mat4> T(nh, Mat4::Identity());
  std::vector<Vec3> centroid(nh, Vec3::Zero());
  for (int k = 0; k < nh; ++k) {
    const std::vector<int> vertices = region.handle_vertices(k);
    for (int v : vertices) centroid[k] += P.row(v).transpose();
    if (!vertices.empty()) centroid[k] /= static_cast<double>(vertices.size());
  }
  int current = -1;  // the handle the next transforms move; -1: all of them
  const auto moved = [&] { return current < 0 ? std::pair{0, nh} : std::pair{current, current + 1}; };  // [k0, k1)
  // A handle's transform is a matrix: it keeps a rotation only up to whole turns, so 190° would be the −170°
  // transform and ±180° the same one, and methods that blend rotations (propagate, gradient, ARAP's start)
  // would turn the other way round. Each handle's turns (in absolute value) must stay below half a turn.
  std::vector<double> turned(nh, 0.0);
  const auto add_turn = [&](double degrees, const std::string& option) {
    const auto [k0, k1] = moved();
    for (int k = k0; k < k1; ++k) {
      turned[k] += degrees;
      if (!(turned[k] < 180)) {
        char total[32];
        std::snprintf(total, sizeof total, "%.7g", turned[k]);
        throw InvalidInput(option + ": the turns of handle " + std::to_string(k) + " add up to " + total +
                           " degrees, half a turn or more. A handle's transform is a matrix, which keeps a rotation "
                           "only up to whole turns (190 degrees is the transform of -170, +180 that of -180), so "
                           "methods that blend rotations could turn the other way round; give less than 180 "
                           "degrees in total per handle (a scale by two or three negative factors holds a half turn)");
      }
    }
  };
  const std::vector<Step> all = steps();
  for (size_t i = 0; i < all.size(); ++i) {
    const Step& s = all[i];
    if (s.option == fixed_) continue;
    if (s.option == handle_) {
      ++current;
      continue;
    }
    const std::string option = s.option->get_name() + " " + s.value;
    if (s.option == about_)  // read with the --rotate or --scale before it
      throw InvalidInput(option + " follows no --rotate or --scale: it names the centre of the one it follows, "
                         "e.g. --rotate 0,0,1,45 --about 1,2,3");
    if (current >= nh)
      throw InvalidInput(option + " follows handle " + std::to_string(current) +
                         ", which the region does not have (" + std::to_string(nh) + " handle(s))");
    Mat4 M = Mat4::Identity();
    if (s.option == translate_) {
      M.topRightCorner<3, 1>() = vec(numbers(option, s.value, {3}, "X,Y,Z"));
    } else if (s.option == rotate_) {
      const auto v = numbers(option, s.value, {4}, "AX,AY,AZ,DEGREES");
      const double largest = vec(v).cwiseAbs().maxCoeff();  // scaled first: 1e-300 squared underflows
      if (largest == 0) throw InvalidInput(option + ": the axis is zero");
      add_turn(std::abs(v[3]), option);
      M.topLeftCorner<3, 3>() =
          Eigen::AngleAxisd(v[3] * kPi / 180, (vec(v) / largest).normalized()).toRotationMatrix();
    } else {
      const auto v = numbers(option, s.value, {1, 3}, "S or SX,SY,SZ");
      const Vec3 factors = v.size() == 1 ? Vec3::Constant(v[0]) : vec(v);
      if (!(factors.array().abs() > 0).all()) throw InvalidInput(option + ": a scale factor is zero");
      // -1,-1,1 is a half turn about z; -1 (all three) a half turn and a mirror, which methods that take a
      // transform's rotation (its polar part, determinant made +1) read as that half turn.
      if ((factors.array() < 0).count() >= 2) add_turn(180, option);
      M.topLeftCorner<3, 3>() = factors.asDiagonal();
    }
    // A rotation or scale is about the point of the --about right after it, else the handle's centroid.
    bool has_about = false;
    Vec3 about = Vec3::Zero();
    std::string step = option;  // the step, as given
    if (s.option != translate_ && i + 1 < all.size() && all[i + 1].option == about_) {
      const Step& next = all[++i];
      step += " --about " + next.value;
      has_about = next.value != "handle-centroid";
      if (has_about) about = vec(numbers("--about " + next.value, next.value, {3}, "X,Y,Z or handle-centroid"));
    }
    const auto [k0, k1] = moved();
    for (int k = k0; k < k1; ++k) {
      const Vec3 c = has_about ? about : transform_point(T[k], centroid[k]);  // where the handle is now
      Mat4 about_c = M;  // M about c: x ↦ c + A (x − c) + t
      about_c.topRightCorner<3, 1>() += c - M.topLeftCorner<3, 3>() * c;
      T[k] = about_c * T[k];
      // Each step, not only the product, stays within msdeform's sizes: --scale 1e200 --scale 1e-200 gave
      // back a product near the identity that had lost the handle's centre to rounding (it moved the handle
      // by minus its centroid).
      if (!(T[k].cwiseAbs().maxCoeff() < kMaxExtent))
        throw InvalidInput(step + ": handle " + std::to_string(k) + "'s transform reaches an entry of " +
                           format_number(T[k].cwiseAbs().maxCoeff()) +
                           " at this step; msdeform works with sizes up to 1e70, in every step of a composition");
      // Two mirrors compose into a turn by twice the angle between their planes: --scale -1,1,1 --scale
      // 1,-1,1 is the half turn that --scale -1,-1,1 is refused as (the steps' own turns do not show it).
      const Mat3 A = T[k].topLeftCorner<3, 3>();
      if (A.determinant() > 0 && !(turn_degrees(A) < 180 - 1e-9))
        throw InvalidInput(
            step + ": the transform of handle " + std::to_string(k) +
            " turns it by half a turn here (mirrors compose into a turn: two across perpendicular "
            "planes make a half turn), and which way round a half turn goes is not defined; give a "
            "transform that turns the handle by less than 180 degrees");
    }
  }
  return T;
}

}  // namespace msd::cli
