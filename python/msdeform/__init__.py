"""msdeform: detail-preserving deformation of triangle meshes (Polygon Mesh Processing, chapter 9).

    import msdeform
    V, F, labels, transforms = msdeform.scene("lift", 10000)        # or msdeform.read_mesh("mesh.off")
    arap = msdeform.Deformer("arap")                                # any name of msdeform.methods()
    arap.prepare(V, F, labels)                                      # labels: msdeform.region(V, ...)
    msdeform.write_mesh("lifted.off", arap.deform(transforms), F)

Arrays are numpy: positions (#V, 3) float64 in mesh units, faces (#F, 3) int32, labels (#V,) int32
selection codes (0 fixed, 1 free, 2+k handle k), transforms one affine 4x4 float64 per handle (a list
or an (H, 4, 4) array). Inputs are copied once into the library's layout; results are returned without
a copy (arrays that own the library's buffers).

Errors: msdeform.InvalidInput and msdeform.TopologyError are ValueErrors, msdeform.UsageError and
msdeform.SolverError RuntimeErrors (all msdeform.Error); missing files raise FileNotFoundError,
unwritable folders PermissionError. Warnings (folds, no convergence, missed constraints) are issued as
msdeform.MsdeformWarning.
"""

try:
    import numpy as _numpy  # noqa: F401  (the extension's array conversions need it)
except ImportError as _e:  # pragma: no cover
    raise ImportError("msdeform needs numpy: use Debian's /usr/bin/python3 with python3-numpy "
                      "(apt-get install python3-numpy), or install numpy for this interpreter") from _e

# The source folder python/msdeform has no compiled extension; it comes first on sys.path when a script
# in python/ runs (python/example.py). Every msdeform folder on sys.path is searched for the extension
# (the build tree's build/python/msdeform, the installed package).
import pkgutil as _pkgutil  # noqa: E402

__path__ = _pkgutil.extend_path(__path__, __name__)

try:
    from . import _msdeform
except ImportError as _e:  # pragma: no cover
    import glob as _glob
    import os as _os
    import sys as _sys
    _built = [p for d in __path__ for p in _glob.glob(_os.path.join(d, "_msdeform*.so"))]
    if not _built:
        raise ImportError(f"msdeform: its compiled extension _msdeform is in none of {list(__path__)}: build it "
                          "(cmake --build build) and run with PYTHONPATH=build/python, or install it "
                          "(cmake --install build)") from _e
    raise ImportError(f"msdeform: cannot load its extension module ({_e}); found {_built}, which loads only in "
                      f"the interpreter it was built for (by default Debian's /usr/bin/python3), not in "
                      f"{_sys.executable} (Python {_sys.version_info[0]}.{_sys.version_info[1]})") from _e

from ._msdeform import (  # noqa: E402
    ControlMesh, Deformer, DeformerTraits, DetailDistortion, Error, FrameReport, InvalidInput, MsdeformWarning,
    ReferenceDistance, RigidityError, SolverError, Stats, TopologyError, UsageError, blas_kernels,
    bounding_box_diagonal, build_info, count_self_intersections, detail_distortion, distance_to_reference,
    handle_error, library_version, method_options, read_def, read_dmat_groups, read_mesh, read_sel, read_soup,
    retain_freed_memory, rigidity_error, scene_names, select_blas_kernels, select_box, select_halfspace,
    select_sphere, self_intersections, shape_change, vertex_normals, volume, volume_change, write_def, write_mesh,
    write_sel,
)
from ._helpers import (  # noqa: E402
    Edit, MethodInfo, constrained_vertices, handle_vertices, identity, load_edit, methods, region, rotation,
    scaling, scene, translation,
)

__version__ = _msdeform.__version__

if library_version() != __version__:  # pragma: no cover
    import warnings as _warnings
    _warnings.warn(f"msdeform: the extension was built against msdeform {__version__} but loads the library "
                   f"{library_version()}: reinstall both from one build", MsdeformWarning)

__all__ = [
    # methods
    "Deformer", "DeformerTraits", "FrameReport", "MethodInfo", "methods", "method_options",
    # files
    "read_mesh", "read_soup", "write_mesh", "read_sel", "write_sel", "read_dmat_groups", "read_def",
    "write_def", "load_edit", "Edit",
    # regions and transforms
    "region", "constrained_vertices", "handle_vertices", "select_box", "select_sphere", "select_halfspace",
    "identity", "translation", "rotation", "scaling",
    # scenes
    "scene", "scene_names", "ControlMesh",
    # metrics
    "handle_error", "rigidity_error", "detail_distortion", "shape_change", "volume", "volume_change",
    "count_self_intersections", "self_intersections", "distance_to_reference", "bounding_box_diagonal",
    "vertex_normals", "Stats", "RigidityError", "DetailDistortion", "ReferenceDistance",
    # errors and warnings
    "Error", "InvalidInput", "TopologyError", "SolverError", "UsageError", "MsdeformWarning",
    # versions
    "__version__", "library_version", "build_info",
    # the process's BLAS kernels
    "select_blas_kernels", "blas_kernels",
]
