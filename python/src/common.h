#pragma once
// Shared by the two translation units of the extension msdeform._msdeform: numpy <-> Eigen conversions
// with argument checks that name the argument and the problem, the exception types, and the warnings.
//
// Copies: the library takes `const Positions&` (column-major #V×3 double) and `const Faces&` (row-major
// #F×3 int), so every array argument is copied once into that layout (whatever its dtype, order and
// strides); outputs are Eigen matrices returned by value, which pybind11 moves into numpy arrays that own
// the library's buffer (no copy; positions come out Fortran-ordered).

#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <string>
#include <vector>

#include "msdeform/core/region.h"
#include "msdeform/core/types.h"

namespace msdpy {

namespace py = pybind11;

// The exception types (created in module.cpp, registered as msdeform.Error and its subclasses).
struct Exceptions {
  PyObject* error = nullptr;          // msdeform.Error(Exception)
  PyObject* invalid_input = nullptr;  // msdeform.InvalidInput(Error, ValueError)
  PyObject* topology = nullptr;       // msdeform.TopologyError(Error, ValueError)
  PyObject* solver = nullptr;         // msdeform.SolverError(Error, RuntimeError)
  PyObject* usage = nullptr;          // msdeform.UsageError(Error, RuntimeError)
  PyObject* warning = nullptr;        // msdeform.MsdeformWarning(UserWarning)
};
Exceptions& exceptions();

// A library message in the Python API's words: read_mesh for load_mesh, the Deformer option for a
// command-line option (remesh_edge_length for --remesh-base, ...), iterations for ARAP's and PriMo's
// max_iterations.
std::string in_python_terms(std::string message);

// Emits each message (in_python_terms) as an msdeform.MsdeformWarning (throws error_already_set when a filter
// turns the warning into an error).
void warn(const std::vector<std::string>& messages);

// str or os.PathLike -> std::string. \throw TypeError.
std::string fspath(py::handle path, const char* what = "path");
// FileNotFoundError / IsADirectoryError unless path names an existing file.
void require_file(const std::string& path);
// FileNotFoundError / NotADirectoryError / PermissionError unless path's folder exists and is writable and
// path is not a read-only file (which an atomic write would replace).
void require_writable(const std::string& path);

// (N, 3) numeric array-like -> Positions (a copy). rows >= 0: N must equal it (one per `per`). \throw TypeError for a
// non-numeric dtype, ValueError for another shape or a non-finite value.
msd::Positions to_positions(py::handle obj, const char* what, long rows = -1, const char* per = "vertex");
// (F, 3) integer array-like (None or an empty array: no faces) -> Faces (a copy). num_vertices >= 0:
// every index must be in [0, num_vertices). \throw TypeError for a non-integer dtype, ValueError for
// another shape or an index out of range.
msd::Faces to_faces(py::handle obj, const char* what, long num_vertices = -1);
// (N,) integer labels (0 fixed, 1 free, 2+k handle k) -> codes. n >= 0: N must equal it. \throw
// TypeError for a non-integer dtype (booleans included), ValueError for another length or a negative code.
std::vector<int> to_codes(py::handle obj, const char* what, long n = -1);
// A 4x4 matrix, a sequence of them or an (H, 4, 4) array -> H matrices. \throw ValueError for another shape.
std::vector<msd::Mat4> to_transforms(py::handle obj, const char* what = "transforms");
// A 3-vector. \throw ValueError.
msd::Vec3 to_vec3(py::handle obj, const char* what);

// Codes -> (N,) int32 array; indices -> (K,) int32 array; transforms -> list of (4, 4) float64 arrays.
py::array_t<int> codes_array(const std::vector<int>& codes);
py::list transforms_list(const std::vector<msd::Mat4>& transforms);

void bind_deformer(py::module_& m);  // deformer.cpp

// Arguments taken as they come and checked by the to_* functions above (so that a wrong shape or dtype
// is a ValueError / TypeError naming the argument, not pybind11's "incompatible function arguments"),
// shown in signatures and help() by what they expect.
template <class Tag>
struct Arg {
  py::object obj;
  operator py::handle() const { return obj; }  // NOLINT(google-explicit-constructor)
  bool is_none() const { return obj.is_none(); }
};
#define MSDPY_ARG(type, text)                                                  \
  struct type##Tag {                                                           \
    static constexpr auto name = py::detail::const_name(text);                 \
  };                                                                           \
  using type = Arg<type##Tag>
MSDPY_ARG(PositionsArg, "numpy.ndarray[numpy.float64[N, 3]]");
MSDPY_ARG(FacesArg, "numpy.ndarray[numpy.int32[F, 3]] | None");
MSDPY_ARG(LabelsArg, "numpy.ndarray[numpy.int32[N]]");
MSDPY_ARG(TransformsArg, "numpy.ndarray[numpy.float64[4, 4]] | list[numpy.ndarray[numpy.float64[4, 4]]]");
MSDPY_ARG(Vec3Arg, "numpy.ndarray[numpy.float64[3]]");
MSDPY_ARG(ValuesArg, "numpy.ndarray[numpy.float64[N]] | None");
MSDPY_ARG(PathArg, "str | os.PathLike");
MSDPY_ARG(OptionalPathArg, "str | os.PathLike | None");
MSDPY_ARG(ResolutionArg, "int | str");
#undef MSDPY_ARG

}  // namespace msdpy

namespace pybind11::detail {
template <class Tag>
struct type_caster<msdpy::Arg<Tag>> {
  PYBIND11_TYPE_CASTER(msdpy::Arg<Tag>, Tag::name);
  bool load(handle src, bool) {
    value.obj = reinterpret_borrow<object>(src);
    return true;
  }
  static handle cast(const msdpy::Arg<Tag>& a, return_value_policy, handle) { return a.obj.inc_ref(); }
};
}  // namespace pybind11::detail
