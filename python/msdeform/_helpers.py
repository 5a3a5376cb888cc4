"""The pure-Python part of msdeform: transforms, regions from masks or predicates, edits and scenes,
the method list. Everything here is re-exported by the package."""

import collections
import copy
import math

import numpy as np

from . import _msdeform as _m

__all__ = [
    "identity", "translation", "rotation", "scaling",
    "region", "constrained_vertices", "handle_vertices",
    "Edit", "scene", "load_edit", "MethodInfo", "methods",
]

# ---------------------------------------------------------------------------------------------------
# Deformer.options: the values in use, a dict that refuses changes (they would not reach the method).


class Options(dict):
    """A method's option values, as Deformer.options returns them: a dict (json.dumps, dict(), ==, pickle
    and copy work as on any dict; copies are plain dicts) whose items cannot be changed. Raises TypeError
    on an assignment: options are set by Deformer(name, **options)."""

    def _refuse(self, *args, **kwargs):
        raise TypeError("Deformer.options is read-only: a change here would not reach the method; set options "
                        "by Deformer(name, **options), e.g. Deformer('arap', iterations=10)")

    __setitem__ = __delitem__ = __ior__ = clear = pop = popitem = setdefault = update = _refuse

    def __reduce__(self):
        return (dict, (dict(self),))

    def __copy__(self):
        return dict(self)

    def __deepcopy__(self, memo):
        return copy.deepcopy(dict(self), memo)


# ---------------------------------------------------------------------------------------------------
# Transforms: 4x4 float64 numpy arrays acting on column vectors (p' = T @ [p, 1]); compose with @.


def _vec3(v, what):
    a = np.asarray(v, dtype=np.float64)
    if a.shape != (3,):
        raise ValueError(f"{what} must be 3 numbers, got shape {a.shape}")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{what} must be finite, got {a}")
    return a


def identity():
    """The 4x4 identity (float64): the transform that leaves a handle at rest."""
    return np.eye(4)


def translation(t):
    """The 4x4 float64 translation by t (3 numbers, mesh units)."""
    T = np.eye(4)
    T[:3, 3] = _vec3(t, "t")
    return T


_AXES = {"x": (1.0, 0.0, 0.0), "y": (0.0, 1.0, 0.0), "z": (0.0, 0.0, 1.0)}


def rotation(axis, degrees, about=None):
    """The 4x4 float64 rotation by `degrees` (counter-clockwise looking down the axis, right-hand rule)
    about `axis` ('x', 'y', 'z' or 3 numbers, any length but zero) through the point `about`
    (3 numbers, mesh units; default the origin). A matrix keeps a rotation only up to whole turns:
    270 degrees gives the matrix of -90, and methods that blend rotations (propagate, gradient, ARAP's
    start) turn the handle the short way round; Deformer.deform warns at a half turn, whose way round is
    not defined. Compose turns of under 180 degrees per handle and frame for a longer path."""
    if isinstance(axis, str):
        if axis.lower() not in _AXES:
            raise ValueError(f"axis must be 'x', 'y', 'z' or a 3-vector, got {axis!r}")
        axis = _AXES[axis.lower()]
    k = _vec3(axis, "axis")
    largest = np.max(np.abs(k))
    if largest == 0:
        raise ValueError("axis must not be zero")
    k = k / largest  # first: the length of a huge or tiny axis would overflow or underflow
    k = k / np.linalg.norm(k)
    if not math.isfinite(float(degrees)):
        raise ValueError(f"degrees must be finite, got {degrees}")
    theta = math.radians(float(degrees))
    K = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    R = np.eye(3) + math.sin(theta) * K + (1.0 - math.cos(theta)) * (K @ K)
    T = np.eye(4)
    T[:3, :3] = R
    if about is not None:
        c = _vec3(about, "about")
        with np.errstate(over="ignore", invalid="ignore"):
            T[:3, 3] = c - R @ c
        if not np.all(np.isfinite(T)):
            raise ValueError(f"about = {c} is too far out: the transform overflows")
    return T


def scaling(factor, about=None):
    """The 4x4 float64 scaling by `factor` (a number, or 3 numbers per axis) about the point `about`
    (default the origin). Raises ValueError for a zero factor (the command line's --scale refuses it too:
    it flattens the handle, and no deformation follows a singular transform)."""
    f = np.asarray(factor, dtype=np.float64)
    f = _vec3(np.full(3, float(f)) if f.ndim == 0 else f, "factor")
    if not np.all(np.abs(f) > 0):
        raise ValueError(f"factor {f.tolist()}: a scale factor is zero (a singular transform)")
    T = np.eye(4)
    T[:3, :3] = np.diag(f)
    if about is not None:
        c = _vec3(about, "about")
        with np.errstate(over="ignore", invalid="ignore"):
            T[:3, 3] = c - f * c
        if not np.all(np.isfinite(T)):
            raise ValueError(f"about = {c} is too far out: the transform overflows")
    return T


# ---------------------------------------------------------------------------------------------------
# Regions: Botsch-Sorkine selection codes, 0 fixed, 1 free, 2+k handle k, one per vertex.


def _mask(selector, V, what):
    n = V.shape[0]
    if callable(selector):
        selector = selector(V)
    a = np.asarray(selector)
    if a.dtype == np.bool_:
        if a.shape != (n,):
            raise ValueError(f"{what}: a boolean mask must have shape ({n},) (one per vertex), got {a.shape}")
        return a.copy()
    mask = np.zeros(n, dtype=bool)
    if a.size == 0:
        return mask
    if not np.issubdtype(a.dtype, np.integer):
        raise TypeError(f"{what} must be a boolean mask, an index array or a callable of V returning one, "
                        f"got dtype {a.dtype}")
    if a.ndim != 1:
        raise ValueError(f"{what}: an index array must be 1-D, got shape {a.shape}")
    bad = a[(a < 0) | (a >= n)]
    if bad.size:
        raise ValueError(f"{what}: vertex index {int(bad[0])} is out of range [0, {n})")
    # An integer 0/1 mask (np.where(c, 1, 0), a mask read from text) would select vertices 0 and 1 only.
    values, counts = np.unique(a, return_counts=True)
    if counts.max() > 1:
        hint = (f"; an integer array of length {n} holding only 0 and 1 looks like a mask: pass it as "
                f"booleans ({what.split('[')[0]}=mask.astype(bool))" if a.shape == (n,) and values.max() <= 1 else "")
        raise ValueError(f"{what}: vertex index {int(values[counts.argmax()])} appears {int(counts.max())} times "
                         f"(an index array lists each vertex once){hint}")
    mask[a] = True
    return mask


def region(V, fixed=None, handles=(), others="free"):
    """Selection codes for an edit of V ((#V, 3) positions): labels, an (#V,) int32 array with 0 on the
    fixed vertices, 2 + k on the vertices of handle k and 1 (free) elsewhere.

    fixed, and each entry of handles, selects vertices as a boolean mask (#V,), an index array, or a
    callable taking V and returning either, e.g. ``lambda V: V[:, 0] < 0.2``. handles is a list (one
    selector per handle; a single array or callable is one handle). others: what the unselected vertices
    are, 'free' (default) or 'fixed'.

    Raises ValueError when there is no handle or a handle selects nothing, a vertex is selected twice (fixed and a handle, or
    two handles, or twice in one index array: an integer 0/1 mask is not a mask), an index is out of range
    or a mask has the wrong length; TypeError for a selector of another kind."""
    V = np.asarray(V)
    if V.ndim != 2 or V.shape[1] != 3:
        raise ValueError(f"V must have shape (N, 3), got shape {V.shape}")
    if others not in ("free", "fixed"):
        raise ValueError(f"others must be 'free' or 'fixed', got {others!r}")
    n = V.shape[0]
    labels = np.full(n, 1 if others == "free" else 0, dtype=np.int32)
    owner = np.full(n, -2, dtype=np.int64)  # -2 unselected, -1 fixed, k handle k
    if fixed is not None:
        m = _mask(fixed, V, "fixed")
        labels[m] = 0
        owner[m] = -1
    if callable(handles) or isinstance(handles, np.ndarray):
        handles = [handles]
    if not isinstance(handles, (list, tuple)):
        raise TypeError(f"handles must be a list of selectors (one per handle), got a {type(handles).__name__}")
    if len(handles) == 0:
        raise ValueError("region(): no handle given (handles=[...]); every edit moves at least one handle")
    if all(isinstance(h, (int, np.integer)) for h in handles):
        raise TypeError(f"handles is a list of selectors, one per handle, and {list(handles)[:4]} is a list of "
                        f"ints: one handle with these vertices is handles=[{list(handles)[:4]}]")
    for k, selector in enumerate(handles):
        what = f"handles[{k}]"
        m = _mask(selector, V, what)
        if not m.any():
            raise ValueError(f"{what} selects no vertex (every handle needs at least one)")
        clash = np.flatnonzero(m & (owner != -2))
        if clash.size:
            v = int(clash[0])
            other = "fixed" if owner[v] == -1 else f"handles[{owner[v]}]"
            raise ValueError(f"vertex {v} is selected by both {other} and {what} ({clash.size} such vertices)")
        labels[m] = 2 + k
        owner[m] = k
    return labels


def constrained_vertices(labels):
    """Indices (int32, ascending) of the fixed and handle vertices of labels: the row order of
    Deformer.deform_to(targets)."""
    return np.flatnonzero(np.asarray(labels) != 1).astype(np.int32)


def handle_vertices(labels, k=0):
    """Indices (int32, ascending) of the vertices of handle k (code 2 + k)."""
    return np.flatnonzero(np.asarray(labels) == 2 + k).astype(np.int32)


# ---------------------------------------------------------------------------------------------------
# Edits


def _same(a, b):
    if a is None or b is None:
        return a is None and b is None
    if isinstance(a, list) or isinstance(b, list):
        return len(a) == len(b) and all(np.array_equal(x, y) for x, y in zip(a, b))
    return np.array_equal(a, b)


class Edit:
    """An edit: name, V (#V, 3) float64, F (#F, 3) int32, labels (#V,) int32 selection codes or None,
    transforms (a list of (4, 4) float64 arrays, one per handle), control (the Loop control mesh of a
    built-in scene, for base='subdivision', else None), path (the mesh file or None) and
    surface_problem (why F is not a manifold triangle mesh, in words, or None).

    Unpacks as ``V, F, labels, transforms = edit``."""

    __slots__ = ("name", "V", "F", "labels", "transforms", "control", "path", "surface_problem")

    def __init__(self, name, V, F, labels=None, transforms=(), control=None, path=None, surface_problem=None):
        self.name = name
        self.V = V
        self.F = F
        self.labels = labels
        self.transforms = list(transforms)
        self.control = control
        self.path = path
        self.surface_problem = surface_problem

    def __iter__(self):
        return iter((self.V, self.F, self.labels, self.transforms))

    def __len__(self):
        return 4

    def __getitem__(self, i):  # edit[0] is V, as for a tuple (V, F, labels, transforms)
        return (self.V, self.F, self.labels, self.transforms)[i]

    def __eq__(self, other):  # equal to the tuple it unpacks to, or to an Edit that unpacks alike
        if isinstance(other, (Edit, tuple)) and len(other) == 4:
            return all(_same(a, b) for a, b in zip(self, other))
        return NotImplemented

    __hash__ = None  # mutable, like the arrays it holds

    def __repr__(self):
        handles = len(self.transforms)
        return (f"<msdeform.Edit {self.name!r}: {self.V.shape[0]} vertices, {self.F.shape[0]} faces, "
                f"{handles} handle transform{'s' if handles != 1 else ''}>")


def scene(name, resolution=10000):
    """A built-in benchmark edit (msdeform.scene_names()): 'lift', 'bend120', 'twist135' on the bumpy
    plane (the unit square with 10x10 smooth bumps of height 0.05) and 'bar-lift', 'bar-bend120',
    'bar-twist135' on the bumpy bar (a tube of radius 0.15 along x, length 1). Fixed for x < 0.2, one
    handle for x > 0.8; lift raises it by 0.3, bend120 / twist135 turn it by 120 / 135 degrees.
    'crease120' bends the plane by 120 degrees within a free strip 0.45 < x < 0.55, tighter than the
    bumps (the seed's Fig. 9.10, where normal displacements cross).

    resolution: about that many vertices (an int, or a string such as '10k', '1M'); the nearest uniform
    Loop refinement is used. Returns an Edit (``V, F, labels, transforms = msdeform.scene('lift')``)
    whose control is the coarse mesh for base='subdivision'.

    Raises msdeform.InvalidInput (ValueError) for an unknown name (listing the known ones) or a
    resolution out of [16, 2e7]; TypeError for a resolution that is neither an int nor a string."""
    if not isinstance(name, str):
        raise TypeError(f"scene name must be a string (msdeform.scene_names()), got {type(name).__name__}")
    if isinstance(resolution, int) and not isinstance(resolution, bool) and not -2**31 <= resolution < 2**31:
        resolution = str(resolution)  # refused by range in words, as the string form is (not a cast error)
    return Edit(**_m._scene(name, resolution))


def load_edit(mesh_path, sel_path=None, def_path=None):
    """An edit from files: a mesh (.off .obj .ply .stl, loaded as it is: point clouds, soups and
    non-manifold meshes load, with the reason in surface_problem), an optional region (.sel, or a libigl
    .dmat group file) and optional handle transforms (.def). Returns an Edit (labels None without a
    region, transforms empty without a .def).

    Raises FileNotFoundError for a missing file; msdeform.InvalidInput (ValueError) naming the file and
    line for a malformed one, or when the region's handle count and the number of matrices differ."""
    return Edit(**_m._load_edit(mesh_path, sel_path, def_path))


# ---------------------------------------------------------------------------------------------------
# The catalogue

MethodInfo = collections.namedtuple("MethodInfo", ["name", "section", "summary", "traits", "options"])
MethodInfo.__doc__ = """A method of the catalogue: name, the section of Polygon Mesh Processing that describes
it, a one-line summary, its DeformerTraits and the names of its keyword options."""


def methods():
    """The catalogue of methods, in its order: a list of MethodInfo(name, section, summary, traits,
    options). Build one with msdeform.Deformer(name, **options)."""
    out = []
    for name, section, summary in _m._catalogue():
        out.append(MethodInfo(name, section, summary, _m.Deformer(name).traits, tuple(_m.method_options(name))))
    return out
