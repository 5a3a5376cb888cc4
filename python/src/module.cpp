// msdeform._msdeform: the module, its exceptions, the argument conversions (common.h), files, regions,
// scenes and metrics. The Deformer class is in deformer.cpp.

#include <unistd.h>

#include <cerrno>
#include <climits>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <optional>

#include "common.h"
#include "msdeform/analysis/metrics.h"
#include "msdeform/analysis/self_intersections.h"
#include "msdeform/core/blas_kernels.h"
#include "msdeform/core/edit_case.h"
#include "msdeform/core/errors.h"
#include "msdeform/core/memory.h"
#include "msdeform/core/mesh.h"
#include "msdeform/core/mesh_io.h"
#include "msdeform/core/region.h"
#include "msdeform/core/scenes.h"
#include "msdeform/core/version.h"
#include "msdeform/deformation/deformer.h"

namespace msdpy {

// ---------------------------------------------------------------------------------------------------
// Exceptions and warnings

Exceptions& exceptions() {
  static Exceptions e;  // the types live as long as the process (never freed: no teardown order issues)
  return e;
}

std::string in_python_terms(std::string message) {
  // The library's messages name its C++ functions and the command line's options; Python has its own
  // names for them (third break test: "load_mesh:" from read_mesh, "max_iterations" for iterations=0).
  static const std::pair<const char*, const char*> kTerms[] = {
      {"load_mesh", "read_mesh"},
      {"load_soup", "read_soup"},
      {"save_mesh", "write_mesh"},
      {"propagate: custom_transfer(", "propagate: transfer("},
      {"NormalDisplacementOptions::max_iterations", "normal_iterations"},
      {"NormalDisplacementOptions::tolerance", "normal_tolerance"},
      {"NormalDisplacementOptions::", ""},
      {"DisplacementVolumeOptions::max_iterations", "volume_iterations"},
      {"DisplacementVolumeOptions::regularization", "volume_regularization"},
      {"DisplacementVolumeOptions::", ""},
      {"arap: max_iterations", "arap: iterations"},
      {"primo: max_iterations", "primo: iterations"},
      {"--remesh-base", "remesh_edge_length"},
      {"--detail-scale", "detail_scale"},
      {"--max-centres", "max_centres"},
      {"--base low-pass", "base='low-pass'"},
      {"(--cage)", "(cage=)"},
      {"--method lattice, cage-mvc, cage-harmonic or rbf",
       "Deformer('lattice'), 'cage-mvc', 'cage-harmonic' or 'rbf'"},
  };
  for (const auto& [from, to] : kTerms)
    for (size_t at = message.find(from); at != std::string::npos;
         at = message.find(from, at + std::strlen(to)))
      message.replace(at, std::strlen(from), to);
  return message;
}

void warn(const std::vector<std::string>& messages) {
  for (const std::string& message : messages)
    if (PyErr_WarnEx(exceptions().warning, in_python_terms(message).c_str(), 1) < 0)
      throw py::error_already_set();
}

namespace {

PyObject* new_exception(const char* name, const char* doc, PyObject* base, PyObject* second = nullptr) {
  PyObject* bases = second ? PyTuple_Pack(2, base, second) : PyTuple_Pack(1, base);
  if (!bases) throw py::error_already_set();
  PyObject* type = PyErr_NewExceptionWithDoc(name, doc, bases, nullptr);
  Py_DECREF(bases);
  if (!type) throw py::error_already_set();
  return type;
}

void register_exceptions(py::module_& m) {
  Exceptions& e = exceptions();
  e.error = new_exception("msdeform.Error",
                          "Base of the errors msdeform's library raises; the message names what is wrong and where "
                          "(file and line, vertex or face) and, where there is one, the remedy.",
                          PyExc_Exception);
  e.invalid_input = new_exception("msdeform.InvalidInput",
                                  "The data is unusable: a malformed file, a wrong count, a non-finite number, an "
                                  "invalid option value (a ValueError).",
                                  e.error, PyExc_ValueError);
  e.topology = new_exception("msdeform.TopologyError",
                             "The mesh or region has a structure the method cannot handle: a non-manifold edge, a "
                             "free component that touches no constrained vertex, ... (a ValueError).",
                             e.error, PyExc_ValueError);
  e.solver = new_exception("msdeform.SolverError",
                           "A numerical solve failed (a matrix that is not positive definite, a non-finite "
                           "result); `index` is the variable or vertex where it showed, or None (a RuntimeError).",
                           e.error, PyExc_RuntimeError);
  e.usage = new_exception("msdeform.UsageError",
                          "A method was called in the wrong order or is not supported by the method: deform() "
                          "before prepare(), deform_to() on a method without vertex targets, ... (a RuntimeError).",
                          e.error, PyExc_RuntimeError);
  e.warning = new_exception("msdeform.MsdeformWarning",
                            "What prepare() or a frame found that the user should know (details close to "
                            "folding, no convergence, constraints missed), each naming a remedy.",
                            PyExc_UserWarning);
  m.attr("Error") = py::handle(e.error);
  m.attr("InvalidInput") = py::handle(e.invalid_input);
  m.attr("TopologyError") = py::handle(e.topology);
  m.attr("SolverError") = py::handle(e.solver);
  m.attr("UsageError") = py::handle(e.usage);
  m.attr("MsdeformWarning") = py::handle(e.warning);

  py::register_exception_translator([](std::exception_ptr p) {
    if (!p) return;
    const Exceptions& x = exceptions();
    try {
      std::rethrow_exception(p);
    } catch (const std::bad_alloc&) {  // pybind11 says "std::bad_alloc"
      PyErr_SetString(PyExc_MemoryError, msd::out_of_memory_message("out of memory").c_str());
    } catch (const msd::InvalidInput& e) {
      PyErr_SetString(x.invalid_input, in_python_terms(e.what()).c_str());
    } catch (const msd::TopologyError& e) {
      PyErr_SetString(x.topology, in_python_terms(e.what()).c_str());
    } catch (const msd::SolverError& e) {
      py::object instance =
          py::reinterpret_borrow<py::object>(x.solver)(in_python_terms(msd::out_of_memory_message(e.what())));
      instance.attr("index") = e.index() >= 0 ? py::object(py::int_(e.index())) : py::object(py::none());
      PyErr_SetObject(x.solver, instance.ptr());
    } catch (const msd::UsageError& e) {
      PyErr_SetString(x.usage, in_python_terms(e.what()).c_str());
    } catch (const msd::Error& e) {
      PyErr_SetString(x.error, in_python_terms(msd::out_of_memory_message(e.what())).c_str());
    }
  });
}

[[noreturn]] void raise_os_error(int err, const std::string& path) {
  errno = err;
  PyErr_SetFromErrnoWithFilename(PyExc_OSError, path.c_str());  // OSError picks the subclass from errno
  throw py::error_already_set();
}

std::string type_name(py::handle obj) { return Py_TYPE(obj.ptr())->tp_name; }

std::string shape_of(const py::array& a) {
  std::string s = "(";
  for (py::ssize_t d = 0; d < a.ndim(); ++d) s += (d ? ", " : "") + std::to_string(a.shape(d));
  return s + (a.ndim() == 1 ? ",)" : ")");
}

// obj as a numpy array (no copy when it is one). \throw TypeError naming the argument.
py::array as_array(py::handle obj, const std::string& what, const char* expected) {
  if (obj.is_none()) throw py::type_error(what + " must be " + expected + ", got None");
  py::array a = py::array::ensure(obj);
  if (!a) throw py::type_error(what + " must be " + expected + ", got " + type_name(obj));
  return a;
}

bool is_integer_kind(char k) { return k == 'i' || k == 'u'; }
bool is_number_kind(char k) { return k == 'f' || k == 'i' || k == 'u'; }

}  // namespace

// ---------------------------------------------------------------------------------------------------
// Conversions (common.h)

std::string fspath(py::handle path, const char* what) {
  PyObject* p = PyOS_FSPath(path.ptr());
  if (!p) {
    PyErr_Clear();
    throw py::type_error(std::string(what) + " must be a str or an os.PathLike, got " + type_name(path));
  }
  py::object o = py::reinterpret_steal<py::object>(p);
  if (PyBytes_Check(p)) return std::string(PyBytes_AS_STRING(p), static_cast<size_t>(PyBytes_GET_SIZE(p)));
  return o.cast<std::string>();
}

void require_file(const std::string& path) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::file_status status = fs::status(path, ec);
  if (!fs::exists(status)) raise_os_error(ENOENT, path);
  if (fs::is_directory(status)) raise_os_error(EISDIR, path);
}

void require_writable(const std::string& path) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (fs::is_directory(fs::status(path, ec))) raise_os_error(EISDIR, path);
  std::string folder = fs::path(path).parent_path().string();
  if (folder.empty()) folder = ".";
  const fs::file_status status = fs::status(folder, ec);
  if (!fs::exists(status)) raise_os_error(ENOENT, folder);
  if (!fs::is_directory(status)) raise_os_error(ENOTDIR, folder);
  if (::access(folder.c_str(), W_OK | X_OK) != 0) raise_os_error(EACCES, folder);
  // A read-only file is meant to stay, as the command line's outputs (fourth break test: write_mesh replaced
  // a 0444 file; root may write anything, so the mode bits are read too).
  const fs::file_status file = fs::status(path, ec);
  if (fs::exists(file) &&
      (::access(path.c_str(), W_OK) != 0 ||
       (file.permissions() & fs::perms::all &
        (fs::perms::owner_write | fs::perms::group_write | fs::perms::others_write)) == fs::perms::none))
    raise_os_error(EACCES, path);
}

msd::Positions to_positions(py::handle obj, const char* what, long rows, const char* per) {
  const std::string name = what;
  py::array a = as_array(obj, name, "an (N, 3) float64 array");
  if (!is_number_kind(a.dtype().kind()))
    throw py::type_error(name + " must hold numbers (an (N, 3) float64 array), got dtype " +
                         std::string(py::str(a.dtype())));
  if (a.ndim() != 2 || a.shape(1) != 3)
    throw py::value_error(name + " must have shape (N, 3), got shape " + shape_of(a));
  if (rows >= 0 && a.shape(0) != rows)
    throw py::value_error(name + " has " + std::to_string(a.shape(0)) + " rows, expected " + std::to_string(rows) +
                          " (one per " + per + ")");
  auto d = py::array_t<double, py::array::forcecast>::ensure(a);
  if (!d) throw py::error_already_set();
  const auto u = d.unchecked<2>();
  msd::Positions P(u.shape(0), 3);
  for (py::ssize_t j = 0; j < 3; ++j)
    for (py::ssize_t i = 0; i < u.shape(0); ++i) {
      const double x = u(i, j);
      if (!std::isfinite(x))
        throw py::value_error(name + "[" + std::to_string(i) + ", " + std::to_string(j) + "] is " +
                              (std::isnan(x) ? "nan" : "infinite") + ": coordinates must be finite");
      P(i, j) = x;
    }
  return P;
}

msd::Faces to_faces(py::handle obj, const char* what, long num_vertices) {
  const std::string name = what;
  if (obj.is_none()) return msd::Faces(0, 3);
  py::array a = as_array(obj, name, "an (F, 3) int32 array");
  if (a.size() == 0 && (a.ndim() == 1 || (a.ndim() == 2 && a.shape(1) == 3))) return msd::Faces(0, 3);
  if (!is_integer_kind(a.dtype().kind()))
    throw py::type_error(name + " must hold vertex indices (an (F, 3) integer array), got dtype " +
                         std::string(py::str(a.dtype())));
  if (a.ndim() != 2 || a.shape(1) != 3)
    throw py::value_error(name + " must have shape (F, 3) (triangles), got shape " + shape_of(a));
  // Read in the array's signedness: an unsigned 2⁶⁴ − 1 read as signed would be named as −1.
  const auto copy = [&](auto tag) {
    using Index = decltype(tag);
    auto d = py::array_t<Index, py::array::forcecast>::ensure(a);
    if (!d) throw py::error_already_set();
    const auto u = d.template unchecked<2>();
    msd::Faces F(u.shape(0), 3);
    for (py::ssize_t i = 0; i < u.shape(0); ++i)
      for (py::ssize_t j = 0; j < 3; ++j) {
        const Index v = u(i, j);
        if (v < 0 || v > INT_MAX || (num_vertices >= 0 && v >= static_cast<Index>(num_vertices)))
          throw py::value_error(
              name + "[" + std::to_string(i) + ", " + std::to_string(j) + "] = " + std::to_string(v) +
              " is not a vertex index" +
              (num_vertices >= 0 ? " (there are " + std::to_string(num_vertices) + " vertices)" : ""));
        F(i, j) = static_cast<int>(v);
      }
    return F;
  };
  return a.dtype().kind() == 'u' ? copy(0ULL) : copy(0LL);
}

std::vector<int> to_codes(py::handle obj, const char* what, long n) {
  const std::string name = what;
  py::array a = as_array(obj, name, "an (N,) int32 array of selection codes");
  const char kind = a.dtype().kind();
  if (kind == 'b')
    throw py::type_error(name + " must be integer selection codes (0 fixed, 1 free, 2+k handle k), got a boolean "
                                "array: build labels from masks with msdeform.region()");
  if (!is_integer_kind(kind) && !(a.size() == 0 && a.ndim() == 1))
    throw py::type_error(name + " must be integer selection codes (0 fixed, 1 free, 2+k handle k), got dtype " +
                         std::string(py::str(a.dtype())));
  if (a.ndim() != 1) throw py::value_error(name + " must have shape (N,), got shape " + shape_of(a));
  if (n >= 0 && a.shape(0) != n)
    throw py::value_error(name + " has " + std::to_string(a.shape(0)) + " entries, but there are " + std::to_string(n) +
                          " vertices (one selection code per vertex)");
  // Read as the array's own signedness: 2^63 as uint64 is no negative number.
  const auto read = [&](auto zero) {
    auto d = py::array_t<decltype(zero), py::array::forcecast>::ensure(a);
    if (!d) throw py::error_already_set();
    const auto u = d.template unchecked<1>();
    std::vector<int> codes(static_cast<size_t>(u.shape(0)));
    for (py::ssize_t i = 0; i < u.shape(0); ++i) {
      const auto c = u(i);
      if (c < zero || c > static_cast<decltype(zero)>(INT_MAX))
        throw py::value_error(name + "[" + std::to_string(i) + "] = " + std::to_string(c) +
                              " is not a selection code (0 fixed, 1 free, 2+k handle k)");
      codes[static_cast<size_t>(i)] = static_cast<int>(c);
    }
    return codes;
  };
  return kind == 'u' ? read(0ULL) : read(0LL);
}

std::vector<msd::Mat4> to_transforms(py::handle obj, const char* what) {
  const std::string name = what;
  const char* expected = "a 4x4 matrix, a list of 4x4 matrices or an (H, 4, 4) array";
  py::array a = as_array(obj, name, expected);
  if (a.size() == 0 && a.ndim() == 1) return {};
  if (!is_number_kind(a.dtype().kind()))
    throw py::type_error(name + " must be " + expected + " of numbers, got dtype " + std::string(py::str(a.dtype())));
  py::ssize_t h = 0;
  if (a.ndim() == 2 && a.shape(0) == 4 && a.shape(1) == 4)
    h = 1;
  else if (a.ndim() == 3 && a.shape(1) == 4 && a.shape(2) == 4)
    h = a.shape(0);
  else
    throw py::value_error(name + " must be " + expected + ", got shape " + shape_of(a));
  auto d = py::array_t<double, py::array::forcecast>::ensure(a);
  if (!d) throw py::error_already_set();
  std::vector<msd::Mat4> out(static_cast<size_t>(h));
  if (h == 1 && d.ndim() == 2) {
    const auto u = d.unchecked<2>();
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c < 4; ++c) out[0](r, c) = u(r, c);
  } else {
    const auto u = d.unchecked<3>();
    for (py::ssize_t k = 0; k < h; ++k)
      for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) out[static_cast<size_t>(k)](r, c) = u(k, r, c);
  }
  return out;
}

msd::Vec3 to_vec3(py::handle obj, const char* what) {
  const std::string name = what;
  py::array a = as_array(obj, name, "a 3-vector");
  if (!is_number_kind(a.dtype().kind()) || a.size() != 3)
    throw py::value_error(name + " must be 3 numbers, got shape " + shape_of(a) + " of dtype " +
                          std::string(py::str(a.dtype())));
  auto d = py::array_t<double, py::array::forcecast>::ensure(a.attr("reshape")(3));
  if (!d) throw py::error_already_set();
  const auto u = d.unchecked<1>();
  msd::Vec3 v(u(0), u(1), u(2));
  if (!v.allFinite()) throw py::value_error(name + " must be finite");
  return v;
}

py::array_t<int> codes_array(const std::vector<int>& codes) {
  py::array_t<int> out(static_cast<py::ssize_t>(codes.size()));
  std::copy(codes.begin(), codes.end(), out.mutable_data());
  return out;
}

py::list transforms_list(const std::vector<msd::Mat4>& transforms) {
  py::list out;
  for (const msd::Mat4& T : transforms) out.append(py::cast(msd::Mat4(T)));
  return out;
}

namespace {

// ---------------------------------------------------------------------------------------------------
// Files, regions, scenes

py::dict load_report(const msd::LoadReport& r) {
  py::dict d;
  d["polygons_triangulated"] = r.polygons_triangulated;
  d["polygons_split_otherwise"] = r.polygons_split_otherwise;
  d["degenerate_faces_skipped"] = r.degenerate_faces_skipped;
  d["repeated_corners_merged"] = r.repeated_corners_merged;
  d["duplicate_faces_dropped"] = r.duplicate_faces_dropped;
  d["faces_flipped"] = r.faces_flipped;
  d["first_ignored_line"] = r.first_ignored_line;
  return d;
}

py::tuple mesh_result(msd::Positions P, msd::Faces F, const msd::LoadReport& report, bool return_report) {
  py::object V = py::cast(std::move(P));  // moved into the array: no copy
  py::object T = py::cast(std::move(F));
  if (return_report) return py::make_tuple(V, T, load_report(report));
  return py::make_tuple(V, T);
}

py::dict edit_dict(msd::EditCase&& c) {
  py::dict d;
  d["name"] = c.name;
  d["V"] = py::cast(std::move(c.P));
  d["F"] = py::cast(std::move(c.F));
  d["labels"] = c.region.num_vertices() > 0 ? py::object(codes_array(c.region.codes())) : py::object(py::none());
  d["transforms"] = transforms_list(c.transforms);
  d["control"] = c.control ? py::cast(std::const_pointer_cast<msd::ControlMesh>(c.control)) : py::object(py::none());
  d["path"] = c.path.empty() ? py::object(py::none()) : py::object(py::str(c.path));
  d["surface_problem"] = c.surface_problem.empty() ? py::object(py::none()) : py::object(py::str(c.surface_problem));
  return d;
}

int resolution_of(py::handle resolution) {
  if (py::isinstance<py::str>(resolution)) return msd::parse_resolution(resolution.cast<std::string>());
  if (py::isinstance<py::bool_>(resolution) || !PyIndex_Check(resolution.ptr()))
    throw py::type_error("resolution must be an int (about that many vertices) or a string such as '10k', got " +
                         type_name(resolution));
  const long long r = resolution.cast<long long>();
  if (r < 16 || r > 20000000)
    throw py::value_error("resolution " + std::to_string(r) + " is out of range [16, 2e7] (vertices)");
  return static_cast<int>(r);
}

void bind_files(py::module_& m) {
  m.def(
      "read_mesh",
      [](PathArg path, bool return_report) {
        const std::string p = fspath(path);
        require_file(p);
        msd::LoadReport report;
        msd::Positions P;
        msd::Faces F;
        {
          py::gil_scoped_release release;
          const msd::Mesh mesh = msd::load_mesh(p, &report);
          P = msd::positions(mesh);
          F = msd::faces(mesh);
        }
        return mesh_result(std::move(P), std::move(F), report, return_report);
      },
      py::arg("path"), py::arg("return_report") = false,
      R"doc(Loads a manifold triangle mesh (.off .obj .ply .stl, by extension).

Returns (V, F): V (#V, 3) float64 in the file's units and vertex order (count and order kept exactly:
.sel files index them), F (#F, 3) int32 triangles (polygons split into fans, faces repeating a vertex
and duplicate faces dropped, faces wound against their neighbours turned over). With
return_report=True: (V, F, report), report a dict counting what loading did to the faces.

Raises FileNotFoundError for a missing file; msdeform.InvalidInput (a ValueError) for a malformed file
(naming the line), a point cloud (no faces) or an unknown extension; msdeform.TopologyError (a
ValueError) for a non-manifold or non-orientable mesh, naming the edge or vertex (read_soup loads it).)doc");
  m.def(
      "read_soup",
      [](PathArg path, bool return_report) {
        const std::string p = fspath(path);
        require_file(p);
        msd::LoadReport report;
        msd::TriangleSoup soup;
        {
          py::gil_scoped_release release;
          soup = msd::load_soup(p, &report);
        }
        return mesh_result(std::move(soup.P), std::move(soup.F), report, return_report);
      },
      py::arg("path"), py::arg("return_report") = false,
      R"doc(Loads any file as it is: a point cloud (F has 0 rows), a polygon soup, a non-manifold or
inconsistently oriented mesh; for the space methods (lattice, cage-*, rbf), which deform any input.

Returns (V, F) as read_mesh (V (#V, 3) float64, F (#F, 3) int32), faces not reoriented; with
return_report=True also the report dict. Raises FileNotFoundError, msdeform.InvalidInput (ValueError).)doc");
  m.def(
      "write_mesh",
      [](PathArg path, PositionsArg V, FacesArg F, ValuesArg scalar, const std::string& scalar_name) {
        const std::string p = fspath(path);
        const msd::Positions P = to_positions(V, "V");
        const msd::Faces T = to_faces(F, "F", P.rows());
        Eigen::VectorXd values;
        msd::SaveOptions options;
        if (!scalar.is_none()) {
          auto a = py::array_t<double, py::array::forcecast>::ensure(scalar);
          if (!a || a.ndim() != 1 || a.shape(0) != P.rows())
            throw py::value_error("scalar must be a (#V,) float array with one value per vertex (" +
                                  std::to_string(P.rows()) + ")");
          values = Eigen::Map<const Eigen::VectorXd>(a.data(), a.shape(0));
          options.vertex_scalar = &values;
          options.scalar_name = scalar_name;
        }
        require_writable(p);
        {
          py::gil_scoped_release release;
          msd::save_mesh(P, T, p, options);
        }
        if (msd::file_extension(p) != ".stl") return;
        // As the command line warns of an STL output (third break test: silent in Python).
        if (const msd::StlReadBack back = msd::stl_read_back(P, T); back.renumbered)
          warn({"write_mesh: " + p + ": STL keeps no vertex list, so the file reads back with " +
                (back.unused + back.merged == 0
                     ? std::string("its vertices renumbered")
                     : std::to_string(back.vertices) + " of the " + std::to_string(P.rows()) + " vertices (" +
                           std::to_string(back.unused) + " that no face uses lost, " +
                           std::to_string(back.merged) + " at the point of another joined), numbered") +
                " by first use in a face; labels made for V select other vertices of it. .ply, .off and .obj "
                "keep the vertices as they are"});
      },
      py::arg("path"), py::arg("V"), py::arg("F") = py::none(), py::arg("scalar") = py::none(),
      py::arg("scalar_name") = "quality",
      R"doc(Saves V (#V, 3) and F (#F, 3) int triangles (None or empty: a point cloud) to path; the format
comes from the extension (.off .obj .ply .stl), full double precision (STL: single). scalar: optional
(#V,) values written as a PLY vertex property named scalar_name. The file is written to a temporary file
and renamed: a failed save leaves an existing file untouched. The arrays are copied once. STL keeps no
vertex list: when the file would read back with other vertex numbers (unused vertices lost, vertices at
one point joined, numbered by first use), an msdeform.MsdeformWarning says so.

Raises FileNotFoundError / PermissionError when the folder is missing or not writable; ValueError for a
wrong shape or index; msdeform.InvalidInput for an unknown extension, non-finite positions, an STL
without faces or a scalar with a format other than PLY.)doc");

  m.def(
      "read_sel",
      [](PathArg path, long num_vertices) {
        const std::string p = fspath(path);
        require_file(p);
        if (num_vertices < 0 || num_vertices > INT_MAX) throw py::value_error("num_vertices must be >= 0");
        return codes_array(msd::read_sel(p, static_cast<int>(num_vertices)).codes());
      },
      py::arg("path"), py::arg("num_vertices"),
      R"doc(Reads a Botsch–Sorkine .sel file: '#' comments, then one code per vertex (0 fixed, 1 free,
2+k handle k). Returns labels, an (num_vertices,) int32 array.

Raises FileNotFoundError; msdeform.InvalidInput (ValueError) naming the file and line for a wrong count
or a code that is not a non-negative integer.)doc");
  m.def(
      "write_sel",
      [](PathArg path, LabelsArg labels) {
        const std::string p = fspath(path);
        const msd::Region region = msd::Region::from_codes(to_codes(labels, "labels"));
        require_writable(p);
        msd::write_sel(region, p);
      },
      py::arg("path"), py::arg("labels"),
      R"doc(Writes labels ((N,) integer codes: 0 fixed, 1 free, 2+k handle k) as a .sel file (atomically).
Raises TypeError / ValueError for labels that are not non-negative integers, msdeform.InvalidInput
(ValueError) for handle codes that are not consecutive (code 3 without code 2), FileNotFoundError /
PermissionError for a missing or read-only folder.)doc");
  m.def(
      "read_dmat_groups",
      [](PathArg path, long num_vertices) {
        const std::string p = fspath(path);
        require_file(p);
        if (num_vertices < 0 || num_vertices > INT_MAX) throw py::value_error("num_vertices must be >= 0");
        return codes_array(msd::read_dmat_groups(p, static_cast<int>(num_vertices)).codes());
      },
      py::arg("path"), py::arg("num_vertices"),
      R"doc(Reads a libigl .dmat group file (one column of num_vertices integers: -1 free, g >= 0 handle g)
as labels ((num_vertices,) int32 selection codes: 1 free, 2+g handle g; no vertex is fixed).
Raises FileNotFoundError; msdeform.InvalidInput (ValueError) for a wrong header, count or value.)doc");
  m.def(
      "read_def",
      [](PathArg path) {
        const std::string p = fspath(path);
        require_file(p);
        return transforms_list(msd::read_def(p));
      },
      py::arg("path"),
      R"doc(Reads a .def file: one affine 4x4 matrix per handle, 16 numbers each, row by row. Returns a list
of (4, 4) float64 arrays (handle k's at index k). Raises FileNotFoundError; msdeform.InvalidInput
(ValueError) when the count is not a multiple of 16, a number is malformed or non-finite, or a last row
is not (0 0 0 1).)doc");
  m.def(
      "write_def",
      [](PathArg path, TransformsArg transforms) {
        const std::string p = fspath(path);
        const std::vector<msd::Mat4> T = to_transforms(transforms);
        require_writable(p);
        msd::write_def(T, p);
      },
      py::arg("path"), py::arg("transforms"),
      R"doc(Writes transforms (a 4x4 matrix, a list of them or an (H, 4, 4) array) as a .def file, 17
significant digits (atomically). Raises ValueError for another shape, FileNotFoundError /
PermissionError for a missing or read-only folder.)doc");

  py::class_<msd::ControlMesh, std::shared_ptr<msd::ControlMesh>>(
      m, "ControlMesh",
      "The coarse Loop control mesh a built-in scene refines: pass it as Deformer(..., base='subdivision', "
      "control=...) to a multiscale method.")
      .def_property_readonly(
          "V", [](const msd::ControlMesh& c) { return msd::Positions(c.P); }, "(#coarse, 3) float64 control points (a copy)")
      .def_property_readonly(
          "F", [](const msd::ControlMesh& c) { return msd::Faces(c.F); }, "(#coarse faces, 3) int32 (a copy)")
      .def("__repr__", [](const msd::ControlMesh& c) {
        return "<msdeform.ControlMesh with " + std::to_string(c.P.rows()) + " vertices and " +
               std::to_string(c.F.rows()) + " faces>";
      });

  m.def(
      "_scene",
      [](const std::string& name, ResolutionArg resolution) {
        const int r = resolution_of(resolution);
        msd::EditCase c;
        {
          py::gil_scoped_release release;
          c = msd::scene_case(name, r);
        }
        return edit_dict(std::move(c));
      },
      py::arg("name"), py::arg("resolution"), "The fields of msdeform.scene() as a dict (see there).");
  m.def(
      "_load_edit",
      [](PathArg mesh, OptionalPathArg sel, OptionalPathArg def) {
        const std::string mp = fspath(mesh, "mesh_path");
        const std::string s = sel.is_none() ? std::string() : fspath(sel, "sel_path");
        const std::string d = def.is_none() ? std::string() : fspath(def, "def_path");
        for (const std::string* p : {&mp, &s, &d})
          if (!p->empty()) require_file(*p);
        msd::EditCase c;
        {
          py::gil_scoped_release release;
          c = msd::load_edit_case(mp, s, d);
        }
        return edit_dict(std::move(c));
      },
      py::arg("mesh_path"), py::arg("sel_path") = py::none(), py::arg("def_path") = py::none(),
      "The fields of msdeform.load_edit() as a dict (see there).");
  m.def("scene_names", &msd::scene_names,
        "The built-in scenes: lift, bend120, twist135 (the bumpy plane: the unit square with 10x10 bumps of "
        "height 0.05), bar-lift, bar-bend120, bar-twist135 (the bumpy bar: a tube of radius 0.15 along x) and "
        "crease120 (the plane bent by 120 degrees within a free strip 0.1 wide, tighter than the bumps: the "
        "seed's Fig. 9.10).");

  m.def(
      "select_box",
      [](PositionsArg V, Vec3Arg lo, Vec3Arg hi) {
        return codes_array(msd::select_box(to_positions(V, "V"), to_vec3(lo, "lo"), to_vec3(hi, "hi")));
      },
      py::arg("V"), py::arg("lo"), py::arg("hi"),
      "Indices (int32, ascending) of the rows of V (#V, 3) inside the axis-aligned box [lo, hi] (bounds included).");
  m.def(
      "select_sphere",
      [](PositionsArg V, Vec3Arg center, double radius) {
        return codes_array(msd::select_sphere(to_positions(V, "V"), to_vec3(center, "center"), radius));
      },
      py::arg("V"), py::arg("center"), py::arg("radius"),
      "Indices (int32, ascending) of the rows of V (#V, 3) within `radius` of `center` (same units as V).");
  m.def(
      "select_halfspace",
      [](PositionsArg V, Vec3Arg point, Vec3Arg normal) {
        return codes_array(msd::select_halfspace(to_positions(V, "V"), to_vec3(point, "point"), to_vec3(normal, "normal")));
      },
      py::arg("V"), py::arg("point"), py::arg("normal"),
      "Indices (int32, ascending) of the rows p of V (#V, 3) with (p - point) . normal >= 0: the side the "
      "normal points to. (The tool's --fixed halfspace:NX,NY,NZ,D selects the other side, n . p < d.)");
}

// ---------------------------------------------------------------------------------------------------
// Metrics

msd::Region region_of(py::handle labels, long n) { return msd::Region::from_codes(to_codes(labels, "labels", n)); }

void bind_metrics(py::module_& m) {
  py::class_<msd::Stats>(m, "Stats", "Summary of a per-vertex error: mean, 95th percentile, max, count.")
      .def_readonly("mean", &msd::Stats::mean)
      .def_readonly("p95", &msd::Stats::p95, "95th percentile (nearest rank)")
      .def_readonly("max", &msd::Stats::max)
      .def_readonly("count", &msd::Stats::count, "how many values were summarised")
      .def("__repr__", [](const msd::Stats& s) {
        return "Stats(mean=" + std::string(py::repr(py::float_(s.mean))) + ", p95=" +
               std::string(py::repr(py::float_(s.p95))) + ", max=" + std::string(py::repr(py::float_(s.max))) +
               ", count=" + std::to_string(s.count) + ")";
      });
  py::class_<msd::RigidityError>(m, "RigidityError", "Result of rigidity_error().")
      .def_readonly("per_vertex", &msd::RigidityError::per_vertex,
                    "(#V,) float64 (read-only view): min over rotations R of the one-ring's weighted squared edge "
                    "misfit, relative to its rest size (dimensionless; a 10% stretch reads 0.01)")
      .def_readonly("stats", &msd::RigidityError::stats, "Stats over the vertices with a neighbour")
      .def("__repr__", [](const msd::RigidityError& r) { return "RigidityError(stats=" + std::string(py::repr(py::cast(r.stats))) + ")"; });
  py::class_<msd::DetailDistortion>(m, "DetailDistortion", "Result of detail_distortion().")
      .def_readonly("per_vertex", &msd::DetailDistortion::per_vertex,
                    "(#V,) float64 (read-only view): |h1 - h0|, the change of the normal-displacement height over "
                    "the faired base, in mesh units; 0 on fixed and handle vertices")
      .def_readonly("scale", &msd::DetailDistortion::scale, "the normaliser of stats (max |h0| on the free vertices)")
      .def_readonly("stats", &msd::DetailDistortion::stats,
                    "Stats of per_vertex / scale on the free vertices (details scaled by s read max ~ |s - 1|)")
      .def_readonly("rest_heights", &msd::DetailDistortion::rest_heights, "(#V,) h0")
      .def_readonly("deformed_heights", &msd::DetailDistortion::deformed_heights, "(#V,) h1")
      .def_readonly("fallback_vertices", &msd::DetailDistortion::fallback_vertices,
                    "vertices whose base-point search fell back to the closest point (less reliable heights)")
      .def("__repr__", [](const msd::DetailDistortion& d) {
        return "DetailDistortion(stats=" + std::string(py::repr(py::cast(d.stats))) + ", scale=" +
               std::string(py::repr(py::float_(d.scale))) + ")";
      });
  py::class_<msd::ReferenceDistance>(m, "ReferenceDistance", "Result of distance_to_reference().")
      .def_readonly("max", &msd::ReferenceDistance::max, "max_i |p_i - q_i| / diagonal")
      .def_readonly("mean", &msd::ReferenceDistance::mean, "mean_i |p_i - q_i| / diagonal")
      .def_readonly("diagonal", &msd::ReferenceDistance::diagonal, "bounding-box diagonal of the reference")
      .def("__repr__", [](const msd::ReferenceDistance& d) {
        return "ReferenceDistance(max=" + std::string(py::repr(py::float_(d.max))) + ", mean=" +
               std::string(py::repr(py::float_(d.mean))) + ")";
      });

  m.def(
      "handle_error",
      [](PositionsArg rest, PositionsArg deformed, LabelsArg labels, TransformsArg transforms) {
        const msd::Positions R = to_positions(rest, "rest");
        const msd::Positions D = to_positions(deformed, "deformed", R.rows());
        return msd::handle_error(R, D, region_of(labels, R.rows()), to_transforms(transforms));
      },
      py::arg("rest"), py::arg("deformed"), py::arg("labels"), py::arg("transforms"),
      R"doc(How far the constraints are from being met, in mesh units: the largest |p' - T_k p| over the
vertices of handle k and |p' - p| over the fixed ones (0 without constrained vertices). rest, deformed:
(#V, 3); labels (#V,) codes; transforms: at least one 4x4 per handle. Raises ValueError for
mismatched shapes or too few transforms.)doc");
  m.def(
      "rigidity_error",
      [](PositionsArg rest, PositionsArg deformed, FacesArg F, const std::string& weights) {
        const msd::Positions R = to_positions(rest, "rest");
        const msd::Positions D = to_positions(deformed, "deformed", R.rows());
        const msd::Faces T = to_faces(F, "F", R.rows());
        msd::RigidityOptions options;
        if (weights == "cotan")
          options.weights = msd::RigidityWeights::Cotan;
        else if (weights == "uniform")
          options.weights = msd::RigidityWeights::Uniform;
        else
          throw py::value_error("weights must be 'cotan' or 'uniform', got '" + weights + "'");
        py::gil_scoped_release release;
        return msd::rigidity_error(R, D, T, options);
      },
      py::arg("rest"), py::arg("deformed"), py::arg("F"), py::arg("weights") = "cotan",
      R"doc(Rigidity error (the ARAP residual of each one-ring) of deformed against rest (both (#V, 3)) on the
triangles F (#F, 3). Returns a RigidityError: per_vertex (#V,) dimensionless values (0 for a rigid
motion, (s - 1)^2 for a uniform scaling by s) and stats (mean, p95, max). weights: 'cotan' (clamped
at 0) or 'uniform'. Raises ValueError for mismatched shapes or indices.)doc");
  m.def(
      "detail_distortion",
      [](PositionsArg rest, PositionsArg deformed, FacesArg F, LabelsArg labels) {
        const msd::Positions R = to_positions(rest, "rest");
        const msd::Positions D = to_positions(deformed, "deformed", R.rows());
        const msd::Faces T = to_faces(F, "F", R.rows());
        const msd::Region region = region_of(labels, R.rows());
        py::gil_scoped_release release;
        return msd::detail_distortion(R, D, T, region);
      },
      py::arg("rest"), py::arg("deformed"), py::arg("F"), py::arg("labels"),
      R"doc(Change of the details (seed 9.3): the free region of rest and of deformed is faired (thin plate)
and the normal-displacement heights over the two bases are compared. Returns a DetailDistortion
(per_vertex |h1 - h0| in mesh units, stats relative to the largest rest height). rest, deformed:
(#V, 3); F (#F, 3); labels (#V,) codes with free vertices. Raises ValueError for mismatched shapes, a
region without free vertices, or a free region that fairing shrinks (its faired base keeps less than half
of its area: a long tube free between its ends); msdeform.SolverError if a fairing fails.)doc");
  m.def(
      "shape_change",
      [](PositionsArg rest, PositionsArg deformed, FacesArg F, LabelsArg labels, py::object transforms) {
        const msd::Positions R = to_positions(rest, "rest");
        const msd::Positions D = to_positions(deformed, "deformed", R.rows());
        const msd::Faces T = to_faces(F, "F", R.rows());
        const msd::Region region = region_of(labels, R.rows());
        const std::vector<msd::Mat4> asked =
            transforms.is_none() ? std::vector<msd::Mat4>() : to_transforms(transforms);
        if (!transforms.is_none() && static_cast<int>(asked.size()) != region.num_handles())
          throw py::value_error("transforms has " + std::to_string(asked.size()) + " matrices for " +
                                std::to_string(region.num_handles()) + " handle(s) in labels");
        msd::check_affine(asked, "shape_change");  // as Deformer.deform: finite, last row (0 0 0 1)
        if (T.rows() == 0) throw py::value_error("F has no faces: there is no shape to measure");
        const msd::ShapeChange c = msd::shape_change(R, D, T, region);
        const std::string warning = msd::shape_change_warning(c, msd::edit_scaling(asked));
        py::dict d;
        d["edges"] = c.edges;
        d["stretched_share"] = c.stretched_share;
        const auto vertex = [](int v) { return v >= 0 ? py::object(py::int_(v)) : py::object(py::none()); };
        d["largest_factor"] = c.largest_factor;
        d["largest_vertex"] = vertex(c.largest_vertex);
        d["largest_growth"] = c.largest_growth;
        d["growth_vertex"] = vertex(c.growth_vertex);
        d["largest_shrink"] = c.largest_shrink;
        d["shrink_vertex"] = vertex(c.shrink_vertex);
        d["area_ratio"] = c.area_ratio;
        d["volume_change"] =
            c.volume_change ? py::object(py::float_(*c.volume_change)) : py::object(py::none());
        d["warning"] = warning.empty() ? py::object(py::none()) : py::object(py::str(warning));
        return d;
      },
      py::arg("rest"), py::arg("deformed"), py::arg("F"), py::arg("labels"),
      py::arg("transforms") = py::none(),
      R"doc(The shape check of `msdeform deform`'s report, which a frame does not make (it is O(#F)): a dict
with edges (the edges measured: those with a free vertex, or between differently placed vertices),
stretched_share (of those, the share whose length changed beyond 1.5x), largest_factor and largest_vertex
(the largest change max(l'/l, l/l') and a vertex of that edge; largest_growth l'/l and largest_shrink
l/l' apart, with growth_vertex and shrink_vertex), area_ratio (of the triangles with a free
vertex), volume_change (closed meshes, else None) and warning (the tool's warning text where an edge
changed beyond 5x, the area beyond 1.5x or below 2/3, or the volume by over 30 %, each beyond what the
handles' own scaling asks; None otherwise). rest, deformed (#V, 3); F (#F, 3), at least one face; labels
(#V,) codes; transforms: the edit's, one per handle: a handle scaled by s asks for edges, areas and
volumes to change by up to s, s^2 and s^3 (the volume is not judged when one mirrors; None: no handle
scales). Raises ValueError for mismatched shapes, no face, or a transform count other
than the handles'; msdeform.InvalidInput for a transform that is not finite or not affine.)doc");
  m.def(
      "volume",
      [](PositionsArg V, FacesArg F) {
        const msd::Positions P = to_positions(V, "V");
        return msd::volume(P, to_faces(F, "F", P.rows()));
      },
      py::arg("V"), py::arg("F"),
      "Signed enclosed volume (mesh units cubed, positive for outward faces) of a closed, consistently "
      "oriented mesh V (#V, 3), F (#F, 3); None if it is not closed.");
  m.def(
      "volume_change",
      [](PositionsArg rest, PositionsArg deformed, FacesArg F) {
        const msd::Positions R = to_positions(rest, "rest");
        const msd::Positions D = to_positions(deformed, "deformed", R.rows());
        return msd::volume_change(R, D, to_faces(F, "F", R.rows()));
      },
      py::arg("rest"), py::arg("deformed"), py::arg("F"),
      "Relative volume change V(deformed) / V(rest) - 1 (a uniform scaling by s gives s**3 - 1) of a closed "
      "mesh; None when the mesh is not closed or its rest volume is 0. rest, deformed (#V, 3), F (#F, 3).");
  m.def(
      "count_self_intersections",
      [](PositionsArg V, FacesArg F) {
        const msd::Positions P = to_positions(V, "V");
        const msd::Faces T = to_faces(F, "F", P.rows());
        py::gil_scoped_release release;
        return msd::count_self_intersections(P, T);
      },
      py::arg("V"), py::arg("F"),
      R"doc(Number of pairs of distinct faces of V (#V, 3), F (#F, 3) that intersect other than along what
they share (CGAL, exact predicates: touching counts). Degenerate faces are not tested. Raises
msdeform.InvalidInput (ValueError) for a face that does not fit a manifold, oriented surface.)doc");
  m.def(
      "self_intersections",
      [](PositionsArg V, FacesArg F) {
        const msd::Positions P = to_positions(V, "V");
        const msd::Faces T = to_faces(F, "F", P.rows());
        std::vector<std::pair<int, int>> pairs;
        int degenerate = 0;
        {
          py::gil_scoped_release release;
          msd::count_self_intersections(P, T, &pairs, &degenerate);
        }
        Eigen::Matrix<int, Eigen::Dynamic, 2, Eigen::RowMajor> out(static_cast<Eigen::Index>(pairs.size()), 2);
        for (size_t i = 0; i < pairs.size(); ++i) out.row(static_cast<Eigen::Index>(i)) << pairs[i].first, pairs[i].second;
        return py::make_tuple(py::cast(std::move(out)), degenerate);
      },
      py::arg("V"), py::arg("F"),
      "As count_self_intersections(), returning (pairs, degenerate_faces): pairs an (K, 2) int32 array of "
      "intersecting face rows (f, g), f < g, sorted; degenerate_faces the number of faces not tested.");
  m.def(
      "distance_to_reference",
      [](PositionsArg V, FacesArg F, PositionsArg Q, FacesArg FQ) {
        const msd::Positions P = to_positions(V, "V");
        const msd::Positions R = to_positions(Q, "Q");
        return msd::distance_to_reference(P, to_faces(F, "F", P.rows()), R, to_faces(FQ, "FQ", R.rows()));
      },
      py::arg("V"), py::arg("F"), py::arg("Q"), py::arg("FQ"),
      "Vertex-to-vertex distance of a result V (#V, 3) to a reference result Q of the same mesh (faces F and "
      "FQ equal), relative to the reference's bounding-box diagonal: a ReferenceDistance (max, mean).");
  m.def(
      "bounding_box_diagonal", [](PositionsArg V) { return msd::bounding_box_diagonal(to_positions(V, "V")); },
      py::arg("V"), "Length of the axis-aligned bounding-box diagonal of V (#V, 3); 0 for fewer than two points.");
  m.def(
      "vertex_normals",
      [](PositionsArg V, FacesArg F) {
        const msd::Positions P = to_positions(V, "V");
        return msd::vertex_normals(P, to_faces(F, "F", P.rows()));
      },
      py::arg("V"), py::arg("F"),
      "Area-weighted unit vertex normals (#V, 3) float64 of V (#V, 3), F (#F, 3); (0, 0, 0) at a vertex "
      "without a non-degenerate face.");
}

}  // namespace
}  // namespace msdpy

PYBIND11_MODULE(_msdeform, m) {
  namespace py = pybind11;
  m.doc() = "msdeform's C++ library (pybind11); use it through the package `msdeform`.";
  m.attr("__version__") = MSD_VERSION_STRING;
  m.def("library_version", &msd::version,
        "Version of the msdeform shared library in use (MAJOR.MINOR.PATCH); msdeform.__version__ is the "
        "version the module was compiled against.");
  m.def("select_blas_kernels", &msd::select_blas_kernels,
        "Where OpenBLAS (behind CHOLMOD) fell back to its slow Prescott kernels on a CPU model it does not know, "
        "switches it to the kernels the CPU allows (SkylakeX with AVX-512, Haswell with AVX2): factorisations "
        "about 1.5x faster on such CPUs. Does nothing when OPENBLAS_CORETYPE is set or the BLAS is not OpenBLAS. "
        "Process-wide (numpy's OpenBLAS too): call it right after import, before any thread uses BLAS; a BLAS "
        "call running meanwhile in another thread can return garbage or hang. Returns blas_kernels().");
  m.def("blas_kernels", &msd::blas_kernels,
        "The OpenBLAS kernels CHOLMOD runs on (e.g. 'SkylakeX', 'Prescott'), or '' for another BLAS.");
  m.def("retain_freed_memory", &msd::retain_freed_memory,
        "Makes glibc's malloc keep freed memory for reuse instead of returning it to the system: large blocks "
        "come from the heap, and up to 1 GiB of free heap top stays mapped (beyond that glibc trims it back to "
        "256 MiB). The large temporaries of prepare() are then not page-faulted in anew each time. Measured on "
        "the 1M-vertex bumpy plane's shell prepare (scene 'lift'): 12.5 s without, 3.9 s with (the msdeform tool "
        "always runs with it). The price: after a peak the process's resident size stays up to 1 GiB above what "
        "it uses. Process-wide (numpy's large arrays too) and opt-in: call it once after import.");
  m.def("build_info", &msd::build_info,
        "How the library was built: the sparse Cholesky in use, Eigen's version and alignment, the CPU target.");
  msdpy::register_exceptions(m);
  msdpy::bind_files(m);
  msdpy::bind_metrics(m);
  msdpy::bind_deformer(m);
}
