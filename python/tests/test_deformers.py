"""The Deformer: every catalogue method on the bumpy plane (handles met, rest pose from identity
transforms), options, frames, the no-copy output, the GIL, and the errors."""

import copy
import json
import os
import pickle
import resource
import subprocess
import sys
import threading
import time
import warnings

import numpy as np
import pytest

import msdeform

from conftest import diagonal

ALL_METHODS = ["shell", "propagate", "gradient", "laplacian", "arap", "primo", "lattice", "cage-mvc",
               "cage-harmonic", "rbf", "multiscale-vectors", "multiscale-normal", "multiscale-volumes",
               "multiscale-transfer"]
# Options that keep the suite fast at this size (the defaults are for 10k+ vertices).
FAST = {"cage-harmonic": {"harmonic_resolution": 32}}


@pytest.fixture(scope="module")
def prepared(lift):
    """prepared(name): the method prepared on the lift scene (once per module)."""
    cache = {}

    def get(name):
        if name not in cache:
            d = msdeform.Deformer(name, **FAST.get(name, {}))
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", msdeform.MsdeformWarning)
                d.prepare(lift.V, lift.F, lift.labels)
            cache[name] = d
        return cache[name]

    return get


def test_catalogue_lists_every_method_with_section_and_summary():
    infos = msdeform.methods()
    assert [m.name for m in infos] == ALL_METHODS
    for m in infos:
        assert m.section.startswith("9.") and len(m.summary) > 20
        assert m.traits.domain in ("surface", "space")
        assert set(m.options) == set(msdeform.method_options(m.name))
    space = {m.name for m in infos if m.traits.domain == "space"}
    assert space == {"lattice", "cage-mvc", "cage-harmonic", "rbf"}
    assert "iterations" in msdeform.method_options("arap")
    assert "default 1000" in msdeform.method_options("arap")["iterations"]
    assert "ks" in msdeform.method_options("multiscale-normal")  # the base method's (shell) options
    assert "anderson" in msdeform.method_options("multiscale-normal", base_method="arap")


@pytest.mark.parametrize("edit", ["lift", "bend"])
@pytest.mark.parametrize("name", ALL_METHODS)
def test_every_method_meets_its_handle(name, edit, prepared, request):
    case = request.getfixturevalue(edit)
    V, F, labels, transforms = case
    d = prepared(name)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", msdeform.MsdeformWarning)
        out = d.deform(transforms)
    assert out.shape == V.shape and out.dtype == np.float64 and np.isfinite(out).all()
    error = msdeform.handle_error(V, out, labels, transforms)
    if d.traits.exact_constraints:
        assert error <= 1e-8, f"{name}: handle error {error}"
    else:
        assert error <= 0.05 * diagonal(V), f"{name}: handle error {error}"
        assert d.frame_report.constraint_error is not None
        assert d.frame_report.constraint_error == pytest.approx(error, rel=1e-6, abs=1e-12)
    # The free strip follows: it moves, and no further than the handle.
    free = labels == 1
    motion = np.linalg.norm(out - V, axis=1)
    handle_motion = np.linalg.norm(out[labels == 2] - V[labels == 2], axis=1).max()
    assert 0.05 * handle_motion < motion[free].mean() < handle_motion


# Identity transforms give the rest pose, to round-off: the linear methods' frames are linear maps of
# T - I, the iterative ones start from rest, the multi-scale ones reconstruct S = B + D from their
# encoding (measured at most 7e-13 of the diagonal, laplacian 5e-13, the others below 1e-14).
IDENTITY_TOLERANCE = 1e-10


@pytest.mark.parametrize("name", ALL_METHODS)
def test_identity_transforms_give_the_rest_pose(name, lift, prepared):
    d = prepared(name)
    d.reset()
    out = d.deform([msdeform.identity()])
    deviation = np.abs(out - lift.V).max() / diagonal(lift.V)
    assert deviation <= IDENTITY_TOLERANCE, f"{name}: {deviation}"


def test_transform_forms_agree_and_the_result_owns_its_data(lift, prepared):
    d = prepared("shell")
    T = lift.transforms[0]
    a = d.deform([T])
    np.testing.assert_array_equal(a, d.deform(T))  # one 4x4: one handle
    np.testing.assert_array_equal(a, d.deform(np.stack([T])))  # an (H, 4, 4) array
    np.testing.assert_array_equal(a, d.deform([T.tolist()]))  # nested lists
    # No copy: the library's column-major buffer, handed over to numpy through a capsule (no other array
    # or object aliases it), writable, and not touched by later frames.
    assert a.flags.f_contiguous and a.flags.writeable
    assert type(a.base).__name__ == "PyCapsule"
    kept = a.copy()
    b = d.deform([msdeform.identity()])
    np.testing.assert_array_equal(a, kept)
    a[:] = 0
    np.testing.assert_array_equal(d.deform([msdeform.identity()]), b)


def test_options_configure_the_method(lift):
    arap = msdeform.Deformer("arap", iterations=7, tolerance=0, anderson=0, energy="spokes-and-rims")
    assert arap.options == {"iterations": 7, "tolerance": 0.0, "anderson": 0, "energy": "spokes-and-rims",
                            "min_weight_ratio": 0.1}
    arap.prepare(lift.V, lift.F, lift.labels)
    arap.deform(lift.transforms)
    report = arap.frame_report
    assert report.iterations == 7 and report.converged  # tolerance 0: exactly `iterations`, as asked
    assert "iterations=7" in repr(arap)
    short = msdeform.Deformer("arap", iterations=2)
    short.prepare(lift.V, lift.F, lift.labels)
    with pytest.warns(msdeform.MsdeformWarning, match="stopped after 2 iterations"):
        short.deform(lift.transforms)
    report = short.frame_report
    assert report.iterations == 2 and not report.converged and report.residual > 0
    assert report.warnings and "raise its iteration limit" in report.warnings[0]

    ms = msdeform.Deformer("multiscale-normal", base_method="arap", iterations=3, detail_scale=0.3)
    assert ms.options["base_method"] == "arap" and ms.options["iterations"] == 3
    assert msdeform.Deformer("multiscale-normal", base_method="shell").options["kb"] == 1.0
    assert msdeform.Deformer("lattice", cells=(4, 3, 2)).options["cells"] == (4, 3, 2)
    assert msdeform.Deformer("lattice", cells=5, seed_least_norm=True).options["seed_least_norm"] is True
    with pytest.raises(TypeError, match="read-only"):  # an assignment would not reach the method
        arap.options["iterations"] = 3
    with pytest.raises(TypeError, match="read-only"):
        arap.options.update(iterations=3)
    assert arap.options["iterations"] == 7
    assert isinstance(arap.options, dict) and json.loads(json.dumps(arap.options)) == arap.options
    for kept in (copy.copy(arap.options), copy.deepcopy(arap.options), pickle.loads(pickle.dumps(arap.options))):
        assert type(kept) is dict and kept == arap.options  # plain dicts, free to change


@pytest.mark.parametrize("name", [m.name for m in msdeform.methods()])
def test_options_given_back_make_the_same_deformer(name):
    # Deformer(name, **d.options) rebuilds d; the options not in use read None (no cage, no remeshed base).
    options = msdeform.Deformer(name).options
    assert msdeform.Deformer(name, **options).options == options
    if name.startswith("multiscale"):
        assert options["remesh_edge_length"] is None and options["control"] is None
    if name.startswith("multiscale") and name != "multiscale-vectors":  # vectors need B's connectivity
        remeshed = msdeform.Deformer(name, base="remeshed", remesh_edge_length=0.5).options
        assert remeshed["remesh_edge_length"] == 0.5 and msdeform.Deformer(name, **remeshed).options == remeshed
    if name.startswith("cage"):
        assert options["cage"] is None
        V = np.array([[x, y, z] for x in (-1, 2) for y in (-1, 2) for z in (-1, 2)], dtype=float)
        F = np.array([[0, 2, 1], [1, 2, 3], [4, 5, 6], [5, 7, 6], [0, 1, 4], [1, 5, 4],
                      [2, 6, 3], [3, 6, 7], [0, 4, 2], [2, 4, 6], [1, 3, 5], [3, 7, 5]], dtype=np.int32)
        given = msdeform.Deformer(name, cage=(V, F)).options  # the generated cage's shape is not in use
        assert given["margin"] is None and given["subdivisions"] is None
        assert msdeform.Deformer(name, **given).options["cage"] is not None


def test_a_python_transfer_function(lift):
    linear = msdeform.Deformer("propagate")
    square = lambda s: s * s  # noqa: E731
    squared = msdeform.Deformer("propagate", transfer=square)
    assert squared.options["transfer"] is square
    assert msdeform.Deformer("propagate", **squared.options).options["transfer"] is square  # it said 'custom'
    for d in (linear, squared):
        d.prepare(lift.V, lift.F, lift.labels)
    a, b = linear.deform(lift.transforms), squared.deform(lift.transforms)
    assert msdeform.handle_error(lift.V, b, lift.labels, lift.transforms) <= 1e-12
    free = lift.labels == 1
    assert (b[free, 2] - lift.V[free, 2]).mean() < (a[free, 2] - lift.V[free, 2]).mean()  # s^2 <= s
    with pytest.raises(ZeroDivisionError):
        msdeform.Deformer("propagate", transfer=lambda s: 1 / 0).prepare(lift.V, lift.F, lift.labels)
    with pytest.raises(TypeError, match=r"option transfer: the callable must return a number"):
        msdeform.Deformer("propagate", transfer=lambda s: "half").prepare(lift.V, lift.F, lift.labels)
    # A value out of [0, 1] is named in a few digits (1e300 was printed with 301).
    with pytest.raises(ValueError, match=r"\) = 1e\+300 at vertex \d+ .*must map \[0, 1\] into \[0, 1\]") as e:
        msdeform.Deformer("propagate", transfer=lambda s: 1e300).prepare(lift.V, lift.F, lift.labels)
    assert len(str(e.value)) < 200


def test_unknown_method_and_options_are_refused_by_name():
    with pytest.raises(ValueError, match="unknown method 'arapp'.*arap, primo"):
        msdeform.Deformer("arapp")
    with pytest.raises(TypeError, match=r"unknown option 'iteration' \(did you mean 'iterations'\?\).*"
                                        r"arap takes: iterations, tolerance, anderson"):
        msdeform.Deformer("arap", iteration=10)
    with pytest.raises(TypeError, match="option 'ks' configures shell .*not arap"):
        msdeform.Deformer("arap", ks=1.0)
    with pytest.raises(TypeError, match="gradient takes no options"):
        msdeform.Deformer("gradient", kb=1.0)
    with pytest.raises(TypeError, match="option iterations must be an int, got float"):
        msdeform.Deformer("arap", iterations=10.0)
    with pytest.raises(TypeError, match="option ks must be a number, got bool"):
        msdeform.Deformer("shell", ks=True)
    with pytest.raises(ValueError, match="option energy must be one of 'spokes', 'spokes-and-rims', got 'rims'"):
        msdeform.Deformer("arap", energy="rims")
    with pytest.raises(ValueError, match="base_method must be a single-scale method"):
        msdeform.Deformer("multiscale-normal", base_method="multiscale-vectors")
    # The library's own check of the value, in the option's Python name (third break test: "max_iterations",
    # and the tolerance printed as "-1.000000").
    with pytest.raises(msdeform.InvalidInput, match=r"arap: iterations must be at least 1 \(got 0\)"):
        msdeform.Deformer("arap", iterations=0)
    with pytest.raises(msdeform.InvalidInput, match=r"primo: iterations must be >= 1"):
        msdeform.Deformer("primo", iterations=0)
    with pytest.raises(msdeform.InvalidInput, match=r"tolerance must lie in \[0, 1\], a fraction of the bounding-box diagonal \(got -1\)"):
        msdeform.Deformer("arap", tolerance=-1)
    # transfer takes a callable too, and the message says so.
    with pytest.raises(TypeError, match="option transfer must be 'linear', 'smoothstep' or a callable t.s., got int"):
        msdeform.Deformer("propagate", transfer=5)
    # Sizes that would exhaust memory are refused by the library, for Python as for the command line.
    with pytest.raises(msdeform.InvalidInput, match=r"Python: cells=N, --lattice-cells\) must be in 1\.\.64, got 3000"):
        msdeform.Deformer("lattice", cells=3000)
    # A 0 beside other counts named the problem as "give all three cell counts or none".
    with pytest.raises(msdeform.InvalidInput, match=r"cell counts must be in 1\.\.64 \(or all 0 to fit them\), got \(0, 2, 2\)"):
        msdeform.Deformer("lattice", cells=(0, 2, 2))
    with pytest.raises(msdeform.InvalidInput, match=r"cell counts must be in 1\.\.64"):
        msdeform.Deformer("lattice", cells=(4, 1000, 4))
    with pytest.raises(msdeform.InvalidInput, match=r"max_centres must be in 1\.\.20000"):
        msdeform.Deformer("rbf", max_centres=10**6)
    with pytest.raises(msdeform.InvalidInput, match=r"harmonic_resolution must be in 4\.\.128"):
        msdeform.Deformer("cage-harmonic", harmonic_resolution=256)
    # A detail scale out of range was accepted here and refused only by prepare(), after the mesh was read.
    with pytest.raises(msdeform.InvalidInput, match=r"the detail scale must be finite and >= 0 \(0 = automatic\), got -1"):
        msdeform.Deformer("multiscale-normal", detail_scale=-1)
    with pytest.raises(ValueError, match=r"option iterations = 9223372036854775808 is out of range"):
        msdeform.Deformer("arap", iterations=2**63)
    with pytest.raises(ValueError, match="control applies to base='subdivision'"):
        msdeform.Deformer("multiscale-normal", control=msdeform.scene("lift", 100).control)
    # Settings of another base or field were accepted and ignored (the command line refused them).
    with pytest.raises(ValueError, match="fairing applies to base='fairing', not base='low-pass'"):
        msdeform.Deformer("multiscale-normal", fairing=2)
    with pytest.raises(ValueError, match="detail_scale applies to the low-pass and remeshed bases, not base='fairing'"):
        msdeform.Deformer("multiscale-normal", base="fairing", detail_scale=0.3)
    with pytest.raises(ValueError, match="low_pass_solver applies to the low-pass and remeshed bases, not base='fairing'"):
        msdeform.Deformer("multiscale-normal", base="fairing", low_pass_solver="factorisation")
    with pytest.raises(ValueError, match="low_pass_solver must be one of 'conjugate-gradients', 'factorisation'"):
        msdeform.Deformer("multiscale-normal", low_pass_solver="cholesky")
    assert msdeform.Deformer("multiscale-normal").options["low_pass_solver"] == "conjugate-gradients"
    assert msdeform.Deformer("multiscale-normal", base="fairing").options["low_pass_solver"] is None
    # Both solvers give the same base (to 1e-9 of the diagonal; the test of low_pass_base checks it closely).
    lift = msdeform.scene("lift", 2000)
    outs = []
    for solver in ("factorisation", "conjugate-gradients"):
        d = msdeform.Deformer("multiscale-normal", detail_scale=0.3, low_pass_solver=solver)
        d.prepare(lift.V, lift.F, lift.labels)
        outs.append(d.deform(lift.transforms))
    assert np.abs(outs[0] - outs[1]).max() < 1e-8
    with pytest.raises(ValueError, match="geodesic_time_factor applies to field='geodesic', not field='harmonic'"):
        msdeform.Deformer("propagate", geodesic_time_factor=2)
    with pytest.raises(ValueError, match="geodesic_time_factor applies to field='geodesic'"):
        msdeform.Deformer("multiscale-normal", base_method="propagate", geodesic_time_factor=2)
    # Where they apply they are taken, and read back; elsewhere they read None.
    assert msdeform.Deformer("multiscale-normal", base="fairing", fairing=3).options["fairing"] == "minimum-variation"
    assert msdeform.Deformer("multiscale-normal", base="fairing").options["detail_scale"] is None
    assert msdeform.Deformer("multiscale-normal").options["fairing"] is None
    assert msdeform.Deformer("propagate", field="geodesic", geodesic_time_factor=2).options["geodesic_time_factor"] == 2
    assert msdeform.Deformer("propagate").options["geodesic_time_factor"] is None


def test_coordinates_that_overflow_lengths_are_named(lift):
    with pytest.raises(msdeform.InvalidInput, match="coordinates too large"):
        msdeform.Deformer("shell").prepare(lift.V * 1e300, lift.F, lift.labels)
    with pytest.raises(msdeform.InvalidInput, match="coordinates too large: the bounding-box diagonal is 1.4"):
        msdeform.Deformer("propagate").prepare(lift.V * 1e150, lift.F, lift.labels)
    with pytest.raises(msdeform.InvalidInput, match="coordinates too small"):
        msdeform.Deformer("arap").prepare(lift.V * 1e-150, lift.F, lift.labels)
    for name in ("arap", "rbf"):  # all at one point: refused, not an inf warning or a silent result
        with pytest.raises(msdeform.InvalidInput, match="no extent"):
            msdeform.Deformer(name).prepare(np.ones_like(lift.V), lift.F, lift.labels)
    d = msdeform.Deformer("shell")
    d.prepare(lift.V, lift.F, lift.labels)
    huge = np.eye(4)
    huge[0, 3] = 1e300
    with pytest.raises(msdeform.InvalidInput, match="has an entry of 1e\\+300"):
        d.deform([huge])


def test_a_deformer_made_without_init_is_refused():
    d = msdeform.Deformer.__new__(msdeform.Deformer)  # no C++ object behind it
    with pytest.raises(TypeError, match="made without __init__"):
        d.prepare(np.zeros((3, 3)), np.array([[0, 1, 2]], dtype=np.int32), np.array([0, 1, 2], dtype=np.int32))
    with pytest.raises(TypeError, match="made without __init__"):
        d.name


def test_frame_errors(lift, prepared):
    fresh = msdeform.Deformer("shell")
    with pytest.raises(msdeform.UsageError, match="before prepare") as info:
        fresh.deform(lift.transforms)
    assert isinstance(info.value, RuntimeError)
    d = prepared("shell")
    T = lift.transforms[0]
    with pytest.raises(ValueError, match=r"2 handle transforms given, the region has 1 handle"):
        d.deform([T, T])
    with pytest.raises(ValueError, match=r"got shape \(3, 4\)"):
        d.deform(T[:3])
    bad = T.copy()
    bad[3, 0] = 1
    with pytest.raises(ValueError, match="not affine"):
        d.deform([bad])
    bad = T.copy()
    bad[0, 0] = np.nan
    with pytest.raises(ValueError, match="non-finite"):
        d.deform([bad])


def test_prepare_errors(lift):
    V, F, labels, _ = lift
    d = msdeform.Deformer("shell")
    with pytest.raises(ValueError, match=r"V must have shape \(N, 3\), got shape \(%d, 2\)" % len(V)):
        d.prepare(V[:, :2], F, labels)
    with pytest.raises(TypeError, match="F must hold vertex indices"):
        d.prepare(V, F.astype(float), labels)
    worse = F.copy()
    worse[3, 1] = len(V)
    with pytest.raises(ValueError, match=r"F\[3, 1\] = %d is not a vertex index" % len(V)):
        d.prepare(V, worse, labels)
    nan = V.copy()
    nan[4, 2] = np.nan
    with pytest.raises(ValueError, match=r"V\[4, 2\] is nan"):
        d.prepare(nan, F, labels)
    with pytest.raises(ValueError, match="surface method needs triangles"):
        d.prepare(V, None, labels)
    # A free vertex that no face uses: nothing determines where it goes (named as such, not as a component).
    lonely = np.vstack([V, [[5.0, 5.0, 5.0]]])
    with pytest.raises(msdeform.TopologyError, match=r"free vertex %d is used by no face" % len(V)):
        msdeform.Deformer("shell").prepare(lonely, F, np.append(labels, 1))
    # An unsigned index is named as it is (2**64 - 1 was shown as -1).
    huge = F.astype(np.uint64)
    huge[5, 1] = np.iinfo(np.uint64).max
    with pytest.raises(ValueError, match=r"F\[5, 1\] = 18446744073709551615 is not a vertex index"):
        d.prepare(V, huge, labels)
    # A prepare the method refuses leaves nothing of the last good one (num_vertices, num_handles were
    # stale). (Arrays refused before the call, like `worse` above, leave the deformer as it was.)
    d.prepare(V, F, labels)
    with pytest.raises(ValueError, match="surface method needs triangles"):
        d.prepare(V, None, labels)
    assert not d.prepared and d.num_vertices == 0 and d.num_handles == 0
    with pytest.raises(msdeform.UsageError, match=r"the last prepare\(\) failed"):
        d.deform([np.eye(4)])


def test_deform_to_matches_affine_targets(lift, prepared):
    V, F, labels, transforms = lift
    d = prepared("shell")
    assert d.traits.vertex_targets
    c = msdeform.constrained_vertices(labels)
    targets = V[c].copy()
    handle = labels[c] == 2
    targets[handle] = targets[handle] @ transforms[0][:3, :3].T + transforms[0][:3, 3]
    np.testing.assert_allclose(d.deform_to(targets), d.deform(transforms), rtol=0, atol=1e-10)
    with pytest.raises(ValueError, match=rf"has {len(c) - 1} rows, expected {len(c)} \(one per constrained vertex\)"):
        d.deform_to(targets[:-1])
    with pytest.raises(msdeform.UsageError, match="not per-vertex targets"):
        prepared("propagate").deform_to(targets)


def test_space_methods_evaluate_their_map_anywhere(lift, prepared):
    rbf = prepared("rbf")
    rbf.reset()
    np.testing.assert_array_equal(rbf.evaluate(lift.V), lift.V)  # identity at rest
    out = rbf.deform(lift.transforms)
    np.testing.assert_allclose(rbf.evaluate(lift.V), out, rtol=0, atol=1e-12)
    mid = rbf.evaluate([[0.5, 0.5, 0.0]])
    assert mid.shape == (1, 3) and 0 < mid[0, 2] < 0.3
    with pytest.raises(msdeform.UsageError, match="surface method"):
        prepared("shell").evaluate(lift.V)
    # A point so far away that the map overflows is named (it returned NaN).
    with pytest.raises(msdeform.SolverError, match=r"sends point 0 \(1e\+103, 0, 0\) to a non-finite position"):
        rbf.evaluate([[1e103, 0, 0]])


def test_space_methods_take_point_clouds(lift):
    lattice = msdeform.Deformer("lattice")
    lattice.prepare(lift.V, None, lift.labels)
    assert lattice.traits.domain == "space" and not lattice.traits.exact_constraints
    out = lattice.deform(lift.transforms)
    assert msdeform.handle_error(lift.V, out, lift.labels, lift.transforms) <= 0.05 * diagonal(lift.V)


def test_initial_guess_and_reset(lift):
    V, F, labels, transforms = lift
    arap = msdeform.Deformer("arap")
    arap.prepare(V, F, labels)
    assert arap.traits.initial_guess and arap.traits.solve == "iterative"
    solved = arap.deform(transforms)
    cold = arap.frame_report.iterations
    assert arap.frame_report.start == "cold start"
    arap.set_initial_guess(solved)
    again = arap.deform(transforms)
    assert arap.frame_report.iterations < cold
    assert arap.frame_report.start == "initial guess"
    np.testing.assert_allclose(again, solved, rtol=0, atol=1e-4 * diagonal(V))
    arap.deform(transforms)
    assert arap.frame_report.start == "last result"
    # A guess above the cold start's energy is not used, and the report says so (it was silent).
    arap.set_initial_guess(V * 1000)
    arap.deform(transforms)
    assert arap.frame_report.start == "cold start" and "start='cold start'" in repr(arap.frame_report)
    arap.reset()
    assert arap.frame_report.iterations == 0
    with pytest.raises(ValueError, match="X has 3 rows"):
        arap.set_initial_guess(V[:3])
    with pytest.raises(msdeform.UsageError, match="takes no initial guess"):
        shell = msdeform.Deformer("shell")
        shell.prepare(V, F, labels)
        shell.set_initial_guess(V)


def test_multiscale_exposes_its_base(lift, prepared):
    d = prepared("multiscale-normal")
    B, FB = d.base
    assert B.shape == lift.V.shape and FB.shape == lift.F.shape
    assert d.detail_scale >= 0
    assert prepared("shell").base is None


def test_prepare_releases_the_gil():
    edit = msdeform.scene("lift", 20000)
    d = msdeform.Deformer("rbf")
    start = time.perf_counter()
    d.prepare(edit.V, edit.F, edit.labels)
    duration = time.perf_counter() - start
    if duration < 0.05:
        pytest.skip(f"prepare took only {duration:.3f} s: too short to see the GIL")
    done = threading.Event()
    thread = threading.Thread(target=lambda: (d.prepare(edit.V, edit.F, edit.labels), done.set()))
    ticks = []
    thread.start()
    while not done.is_set():
        ticks.append(time.perf_counter())
    thread.join()
    gaps = np.diff(ticks)
    # Held, the GIL would stop this loop for the whole prepare(); released, only for the thread's
    # Python-level moments (the interpreter's switch interval, 5 ms).
    assert gaps.max() < 0.5 * duration, f"the main thread stalled {gaps.max():.3f} s of a {duration:.3f} s prepare"


@pytest.mark.parametrize("name,options", [("propagate", {}), ("propagate", {"field": "geodesic"}),
                                          ("shell", {}), ("gradient", {}), ("arap", {})])
def test_needles_and_zero_area_faces_move_with_their_neighbours(lift, name, options):
    """Issue 14, kind 4: a needle, a zero-area triangle and a vertex glued on by a zero-area triangle
    (a twin of its neighbour) deform like the surface around them: no refusal, no jump."""
    V, F, labels, T = lift
    free = np.where(labels == 1)[0]
    v = free[len(free) // 2]
    face = F[np.any(F == v, axis=1)][0]
    a, b = [w for w in face if w != v]
    needle = V.copy()
    needle[v] = 0.5 * (V[a] + V[b]) + 1e-12
    zero = V.copy()
    zero[v] = 0.5 * (V[a] + V[b])
    for X in (needle, zero):
        d = msdeform.Deformer(name, **options)
        d.prepare(X, F, labels)
        out = d.deform(T)
        assert np.isfinite(out).all()
        # v sits on the edge (a, b): it moves as the mean of the two.
        motion = 0.5 * ((out[a] - X[a]) + (out[b] - X[b]))
        assert np.linalg.norm((out[v] - X[v]) - motion) <= 0.05 * np.linalg.norm(motion)
    # A twin w of vertex v (same position), reachable through a zero-area triangle (v, b, w).
    row = int(np.where(np.any(F == v, axis=1))[0][0])
    f0 = [int(x) for x in F[row]]
    k = f0.index(v)
    b, c = f0[(k + 1) % 3], f0[(k + 2) % 3]
    w = len(V)
    V2 = np.vstack([V, V[v]])
    F2 = np.vstack([F, [[w, b, c]]]).astype(np.int32)
    F2[row] = [v, b, w]
    labels2 = np.append(labels, 1).astype(np.int32)
    d = msdeform.Deformer(name, **options)
    d.prepare(V2, F2, labels2)
    out = d.deform(T)
    assert np.isfinite(out).all()
    assert np.linalg.norm(out[w] - out[v]) <= 0.02 * np.linalg.norm(out[v] - V2[v])


def test_retain_freed_memory_serves_large_arrays_from_the_heap(lift):
    # glibc maps a 64 MB block on its own (mmap) by default; after the call it comes from the heap, which
    # keeps it for reuse once freed. Process-wide: the tests after this one run as the msdeform tool does.
    msdeform.retain_freed_memory()
    block = np.ones(8 << 20)
    with open("/proc/self/maps") as maps:
        heap = [tuple(int(a, 16) for a in line.split()[0].split("-"))
                for line in maps if line.rstrip().endswith("[heap]")]
    assert any(lo <= block.ctypes.data < hi for lo, hi in heap)
    V, F, labels, transforms = lift
    shell = msdeform.Deformer("shell")
    shell.prepare(V, F, labels)
    assert np.isfinite(shell.deform(transforms)).all()


def test_out_of_memory_names_the_address_space_limit():
    # Under ulimit -v, Python said "std::bad_alloc" (or msdeform's "out of memory") without the limit.
    code = ("import msdeform\ntry:\n    msdeform.scene('lift', 20_000_000)\n"
            "except MemoryError as e:\n    print('MemoryError:', e)\n")
    limit = 600 << 20
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120,
                            env=dict(os.environ, OPENBLAS_NUM_THREADS="1"),  # no BLAS worker (README)
                            preexec_fn=lambda: resource.setrlimit(resource.RLIMIT_AS, (limit, limit)))
    assert result.stdout.strip() == ("MemoryError: out of memory under the address-space limit (ulimit -v) of "
                                     "600 MB: raise the limit"), result.stderr


def test_a_mirrored_or_collapsed_handle_is_warned_about(prepared):
    # The checks lived in the msdeform tool only: a Python frame mirrored or collapsed a handle in silence.
    d = prepared("shell")
    for matrix, said in [(np.diag([-1.0, 1, 1, 1]), "is a reflection: it turns the handle inside out"),
                         (np.diag([0.0, 0, 0, 1]), "is singular: it collapses the handle to a point")]:
        with pytest.warns(msdeform.MsdeformWarning, match=said):
            d.deform([matrix])
        assert any(said in w for w in d.frame_report.warnings)
