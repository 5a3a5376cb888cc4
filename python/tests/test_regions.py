"""Regions: labels from masks, index arrays and predicates; the selection helpers; label validation."""

import numpy as np
import pytest

import msdeform


def test_region_from_predicates_is_the_scenes_region(lift):
    labels = msdeform.region(lift.V, fixed=lambda V: V[:, 0] < 0.2, handles=[lambda V: V[:, 0] > 0.8])
    assert labels.dtype == np.int32 and labels.shape == (len(lift.V),)
    np.testing.assert_array_equal(labels, lift.labels)


def test_region_selectors_agree(lift):
    V = lift.V
    fixed, handle = V[:, 0] < 0.2, V[:, 0] > 0.8
    by_mask = msdeform.region(V, fixed=fixed, handles=[handle])
    by_index = msdeform.region(V, fixed=np.flatnonzero(fixed), handles=[np.flatnonzero(handle).tolist()])
    single = msdeform.region(V, fixed=fixed, handles=handle)  # one array: one handle
    np.testing.assert_array_equal(by_mask, by_index)
    np.testing.assert_array_equal(by_mask, single)


def test_region_two_handles_and_others_fixed(lift):
    V = lift.V
    labels = msdeform.region(V, handles=[V[:, 1] < 0.3, lambda V: V[:, 1] > 0.7], others="fixed")
    np.testing.assert_array_equal(np.unique(labels), [0, 2, 3])
    np.testing.assert_array_equal(msdeform.handle_vertices(labels, 1), np.flatnonzero(V[:, 1] > 0.7))
    np.testing.assert_array_equal(msdeform.constrained_vertices(labels), np.arange(len(V)))


def test_region_errors(lift):
    V = lift.V
    with pytest.raises(ValueError, match=r"selected by both fixed and handles\[0\]"):
        msdeform.region(V, fixed=V[:, 0] < 0.5, handles=[V[:, 0] > 0.4])
    with pytest.raises(ValueError, match=r"handles\[1\] selects no vertex"):
        msdeform.region(V, handles=[[0], V[:, 0] > 5])
    with pytest.raises(ValueError, match=f"index {len(V)} is out of range"):
        msdeform.region(V, handles=[[0, len(V)]])
    with pytest.raises(ValueError, match=r"shape \(%d,\)" % len(V)):
        msdeform.region(V, handles=[np.ones(3, dtype=bool)])
    with pytest.raises(TypeError, match="boolean mask, an index array"):
        msdeform.region(V, handles=[np.array([0.5])])
    with pytest.raises(ValueError, match=r"shape \(N, 3\)"):
        msdeform.region(V[:, :2])
    with pytest.raises(ValueError, match="no handle given"):
        msdeform.region(V, fixed=[0])
    with pytest.raises(TypeError, match="handles must be a list of selectors .* got a dict"):
        msdeform.region(V, handles={0: [9]})
    with pytest.raises(TypeError, match="got a NoneType"):
        msdeform.region(V, handles=None)
    with pytest.raises(TypeError, match=r"is a list of ints: one handle with these vertices is handles=\[\[2, 3\]\]"):
        msdeform.region(V, handles=[2, 3])
    # An integer 0/1 mask fixed vertices 0 and 1 only (break test: 2 of 328), without a word.
    for dtype in (int, np.uint8):
        with pytest.raises(ValueError, match=r"fixed: vertex index [01] appears \d+ times .*looks like a mask: pass it "
                                             r"as booleans \(fixed=mask.astype\(bool\)\)"):
            msdeform.region(V, fixed=(V[:, 0] < 0.2).astype(dtype), handles=[V[:, 0] > 0.8])
    with pytest.raises(ValueError, match=r"handles\[0\]: vertex index 3 appears 2 times \(an index array lists each vertex once\)$"):
        msdeform.region(V, handles=[[3, 4, 3]])


def test_selection_helpers_match_numpy(lift):
    V = lift.V
    box = msdeform.select_box(V, (0.1, 0.2, -1), (0.4, 0.6, 1))
    inside = np.all((V >= [0.1, 0.2, -1]) & (V <= [0.4, 0.6, 1]), axis=1)
    np.testing.assert_array_equal(box, np.flatnonzero(inside))
    assert box.dtype == np.int32
    ball = msdeform.select_sphere(V, (0.5, 0.5, 0), 0.25)
    np.testing.assert_array_equal(ball, np.flatnonzero(np.linalg.norm(V - [0.5, 0.5, 0], axis=1) <= 0.25))
    half = msdeform.select_halfspace(V, (0.7, 0, 0), (1, 0, 0))
    np.testing.assert_array_equal(half, np.flatnonzero(V[:, 0] >= 0.7))
    with pytest.raises(ValueError, match="3 numbers"):
        msdeform.select_sphere(V, (0.5, 0.5), 0.25)
    # What the command line refuses (a negative radius selected by its square, a zero normal everything).
    with pytest.raises(ValueError, match="radius finite and >= 0, got radius -1"):
        msdeform.select_sphere(V, (0, 0, 0), -1)
    with pytest.raises(ValueError, match="the normal not zero"):
        msdeform.select_halfspace(V, (0, 0, 0), (0, 0, 0))


def test_labels_are_validated_by_prepare(lift):
    V, F, labels, _ = lift
    shell = msdeform.Deformer("shell")
    with pytest.raises(ValueError, match=f"labels has {len(V) - 1} entries, but there are {len(V)} vertices"):
        shell.prepare(V, F, labels[:-1])
    bad = labels.copy()
    bad[5] = -1
    with pytest.raises(ValueError, match=r"labels\[5\] = -1 is not a selection code"):
        shell.prepare(V, F, bad)
    huge = labels.astype(np.uint64)
    huge[5] = 2**63  # was printed as -9223372036854775808
    with pytest.raises(ValueError, match=r"labels\[5\] = 9223372036854775808 is not a selection code"):
        shell.prepare(V, F, huge)
    with pytest.raises(TypeError, match="boolean array"):
        shell.prepare(V, F, labels == 2)
    with pytest.raises(TypeError, match="dtype float64"):
        shell.prepare(V, F, labels.astype(np.float64))
    with pytest.raises(ValueError, match="no handle"):
        shell.prepare(V, F, np.minimum(labels, 1))
    gap = labels.copy()
    gap[gap == 2] = 3  # handle 1 without handle 0
    with pytest.raises(ValueError, match="handle 0 .* has no vertex"):
        shell.prepare(V, F, gap)
    assert not shell.prepared
