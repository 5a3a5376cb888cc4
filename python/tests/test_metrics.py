"""Metrics against what they are defined to give on known motions."""

import numpy as np
import pytest

import msdeform

from conftest import diagonal


def cube():
    """The unit cube, 12 outward triangles."""
    V = np.array([[x, y, z] for z in (0, 1) for y in (0, 1) for x in (0, 1)], dtype=float)
    F = np.array([[0, 2, 1], [1, 2, 3], [4, 5, 6], [5, 7, 6], [0, 1, 4], [1, 5, 4],
                  [2, 6, 3], [3, 6, 7], [0, 4, 2], [2, 4, 6], [1, 3, 5], [3, 7, 5]], dtype=np.int32)
    return V, F


def apply(T, V):
    return V @ T[:3, :3].T + T[:3, 3]


def test_handle_error_is_the_largest_constraint_miss(lift):
    V, F, labels, transforms = lift
    target = V.copy()
    target[labels == 2] = apply(transforms[0], V[labels == 2])
    moved = target.copy()
    handle, fixed = np.flatnonzero(labels == 2), np.flatnonzero(labels == 0)
    moved[handle[3]] += [0, 0.01, 0]
    moved[fixed[7]] += [0.02, 0, 0]
    moved[labels == 1] += 5  # free vertices do not count
    assert msdeform.handle_error(V, moved, labels, transforms) == pytest.approx(0.02, rel=1e-12)
    with pytest.raises(ValueError, match="rows"):
        msdeform.handle_error(V, moved[:-1], labels, transforms)


def test_shape_change_is_the_tools_check():
    # A frame checks no proportions (the tool's report did, O(#F)): shape_change gives Python the same
    # numbers and warning, so a shell torn by a bend is told from ARAP's.
    V, F, labels, T = msdeform.scene("bend120", 2000)
    results = {}
    for name in ("shell", "arap"):
        d = msdeform.Deformer(name)
        d.prepare(V, F, labels)
        results[name] = msdeform.shape_change(V, d.deform(T), F, labels, T)
    assert results["shell"]["largest_factor"] > 5 and results["shell"]["largest_vertex"] is not None
    assert "does not keep the shape's proportions" in results["shell"]["warning"]
    assert results["arap"]["largest_factor"] < 1.5 and results["arap"]["warning"] is None
    assert results["arap"]["volume_change"] is None  # an open plane
    doubled = msdeform.shape_change(V, 2 * V, F, labels, [msdeform.scaling(2)])
    assert doubled["area_ratio"] == pytest.approx(4) and doubled["warning"] is None  # the edit asks for it
    # A handle scaled by 1.001 asks for areas of x1 to x1.002, not x4 (any scale silenced the check).
    slightly = msdeform.shape_change(V, 2 * V, F, labels, [msdeform.scaling(1.001)])
    assert "area changed x4 (the handles ask for x1 to x1.002)" in slightly["warning"]
    assert doubled["largest_growth"] == pytest.approx(2) and doubled["largest_shrink"] == pytest.approx(1)
    assert doubled["growth_vertex"] is not None and doubled["shrink_vertex"] is None  # no edge shrank
    ten = msdeform.shape_change(V, 10 * V, F, labels, [msdeform.scaling(10)])
    assert ten["largest_factor"] == pytest.approx(10) and ten["warning"] is None  # asked for (it warned)
    with pytest.raises(ValueError):
        msdeform.shape_change(V, V[:-1], F, labels)
    with pytest.raises(ValueError, match="2 matrices for 1 handle"):
        msdeform.shape_change(V, V, F, labels, [msdeform.scaling(2)] * 2)
    with pytest.raises(ValueError, match="no faces"):
        msdeform.shape_change(V, V, F[:0], labels)
    # Transforms that Deformer.deform refuses (the second break test: NaN gave "the handles ask for
    # x3.212e-311 to x1", inf dropped the volume check).
    for bad in (np.full((4, 4), np.nan), np.diag([np.inf, 1, 1, 1]), np.eye(4) + np.eye(4)[::-1]):
        with pytest.raises(msdeform.InvalidInput, match="shape_change"):
            msdeform.shape_change(V, V, F, labels, [bad])


def test_rigidity_error_of_rigid_and_scaled_shapes(lift):
    V, F, _, _ = lift
    T = msdeform.rotation((1, 1, 0), 70, about=(0.3, 0.2, 0.1)) @ msdeform.translation((1, 2, 3))
    rigid = msdeform.rigidity_error(V, apply(T, V), F)
    assert rigid.per_vertex.shape == (len(V),) and rigid.stats.max < 1e-12
    scaled = msdeform.rigidity_error(V, 1.1 * V, F, weights="uniform")
    np.testing.assert_allclose(scaled.per_vertex, 0.01, rtol=1e-9)  # (s - 1)^2
    assert scaled.stats.count == len(V)


def test_volume_and_volume_change_of_a_closed_mesh(lift):
    V, F = cube()
    assert msdeform.volume(V, F) == pytest.approx(1.0, rel=1e-14)
    assert msdeform.volume_change(V, 2 * V, F) == pytest.approx(7.0, rel=1e-14)
    assert msdeform.volume_change(lift.V, lift.V, lift.F) is None  # the plane is open


def test_self_intersections(lift):
    assert msdeform.count_self_intersections(lift.V, lift.F) == 0
    V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0.2, 0.2, -1], [0.3, 0.2, 1], [0.2, 0.3, 1]], dtype=float)
    F = np.array([[0, 1, 2], [3, 4, 5]], dtype=np.int32)  # the second triangle pierces the first
    assert msdeform.count_self_intersections(V, F) == 1
    pairs, degenerate = msdeform.self_intersections(V, F)
    np.testing.assert_array_equal(pairs, [[0, 1]])
    assert degenerate == 0


def test_detail_distortion_and_reference_distance_of_the_rest_shape(lift):
    V, F, labels, _ = lift
    same = msdeform.detail_distortion(V, V, F, labels)
    assert same.per_vertex.shape == (len(V),) and same.stats.max < 1e-9 and same.scale > 0
    doubled = V.copy()
    doubled[:, 2] *= 2  # the plane's details (bumps in z) twice as tall
    assert msdeform.detail_distortion(V, doubled, F, labels).stats.max == pytest.approx(1.0, abs=0.1)
    d = msdeform.distance_to_reference(V, F, V, F)
    assert d.max == 0 and d.diagonal == pytest.approx(diagonal(V))
    assert msdeform.bounding_box_diagonal(V) == pytest.approx(diagonal(V))
