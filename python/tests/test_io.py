"""Files: meshes, soups and point clouds, .sel, .def and .dmat, edits, and the errors for missing or
malformed files."""

import warnings

import numpy as np
import pytest

import msdeform


@pytest.mark.parametrize("ext", [".off", ".obj", ".ply"])
def test_mesh_round_trip_keeps_vertices_and_faces_exactly(tmp_path, lift, ext):
    path = tmp_path / f"plane{ext}"
    msdeform.write_mesh(path, lift.V, lift.F)
    V, F = msdeform.read_mesh(path)
    assert V.dtype == np.float64 and V.shape == lift.V.shape
    assert F.dtype == np.int32 and F.shape == lift.F.shape
    np.testing.assert_array_equal(V, lift.V)  # full double precision
    np.testing.assert_array_equal(F, lift.F)


def test_read_mesh_accepts_str_paths_and_reports_what_loading_did(tmp_path):
    path = tmp_path / "quad.off"
    path.write_text("OFF\n5 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n2 2 2\n4 0 1 2 3\n3 0 1 2\n")
    V, F, report = msdeform.read_mesh(str(path), return_report=True)
    assert V.shape == (5, 3)  # the unreferenced vertex is kept: .sel files index the file's vertices
    assert F.shape == (2, 3)  # the quad's fan (0 1 2) (0 2 3); the triangle 0 1 2 again is dropped
    assert report["polygons_triangulated"] == 1
    assert report["duplicate_faces_dropped"] == 1


def test_point_cloud_round_trip_and_read_mesh_refuses_it(tmp_path, lift):
    path = tmp_path / "cloud.ply"
    msdeform.write_mesh(path, lift.V)  # no faces
    V, F = msdeform.read_soup(path)
    np.testing.assert_array_equal(V, lift.V)
    assert F.shape == (0, 3) and F.dtype == np.int32
    with pytest.raises(ValueError, match="face"):
        msdeform.read_mesh(path)


def test_write_mesh_scalar_property(tmp_path, lift):
    path = tmp_path / "height.ply"
    msdeform.write_mesh(path, lift.V, lift.F, scalar=lift.V[:, 2], scalar_name="height")
    assert b"property double height" in path.read_bytes()[:1000]
    with pytest.raises(ValueError, match="one value per vertex"):
        msdeform.write_mesh(path, lift.V, lift.F, scalar=lift.V[:10, 2])
    # Names msdeform's own reader would refuse are refused before writing (the file stays as it was).
    before = path.read_bytes()
    for name in ["x", "a b", ""]:
        with pytest.raises(ValueError, match="one word of visible characters other than x, y and z"):
            msdeform.write_mesh(path, lift.V, lift.F, scalar=lift.V[:, 2], scalar_name=name)
    assert path.read_bytes() == before
    # NaN is refused as in the positions, naming the vertex (third break test: written without a word).
    scalar = lift.V[:, 2].copy()
    scalar[7] = np.nan
    with pytest.raises(msdeform.InvalidInput, match="scalar is NaN or inf at vertex 7; nothing written"):
        msdeform.write_mesh(path, lift.V, lift.F, scalar=scalar)
    assert path.read_bytes() == before


def test_write_mesh_warns_when_an_stl_renumbers_the_vertices(tmp_path, lift):
    # Third break test: an unused vertex was lost without a word (the command line warns).
    V = np.vstack([lift.V, [[9.0, 9.0, 9.0]]])
    with pytest.warns(msdeform.MsdeformWarning, match=f"reads back with {len(lift.V)} of the {len(V)} vertices \\(1 "):
        msdeform.write_mesh(tmp_path / "a.stl", V, lift.F)
    assert msdeform.read_mesh(tmp_path / "a.stl")[0].shape == lift.V.shape
    # What an STL gave back is written back without a warning.
    W, G = msdeform.read_mesh(tmp_path / "a.stl")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        msdeform.write_mesh(tmp_path / "b.stl", W, G)


def test_write_mesh_keeps_a_read_only_file(tmp_path, lift):
    # Fourth break test: a 0444 file was replaced (the command line refuses read-only outputs).
    path = tmp_path / "kept.off"
    path.write_text("OFF\n0 0 0\n")
    path.chmod(0o444)
    with pytest.raises(PermissionError):
        msdeform.write_mesh(path, lift.V, lift.F)
    assert path.read_text() == "OFF\n0 0 0\n"


def test_option_and_metric_messages_use_the_python_names(lift):
    # Fourth break test: encoding options were refused only by prepare(), in C++ words; tolerances above 1
    # (a fraction of the diagonal) stopped ARAP after one iteration as "converged"; detail_distortion without
    # a fixed or handle vertex spoke of a fairing the user never called.
    with pytest.raises(msdeform.InvalidInput, match=r"^relaxation must be in \(0, 2\), got 5$"):
        msdeform.Deformer("multiscale-volumes", relaxation=5.0)
    with pytest.raises(msdeform.InvalidInput, match=r"^normal_tolerance must be finite and > 0, got -1$"):
        msdeform.Deformer("multiscale-normal", normal_tolerance=-1.0)
    with pytest.raises(msdeform.InvalidInput, match=r"^volume_iterations must be >= 0, got -1$"):
        msdeform.Deformer("multiscale-volumes", volume_iterations=-1)
    with pytest.raises(msdeform.InvalidInput, match=r"tolerance must lie in \[0, 1\]"):
        msdeform.Deformer("arap", tolerance=1e9)
    with pytest.raises(msdeform.InvalidInput, match="^write_mesh: .*unknown format"):
        msdeform.write_mesh("x.abc", lift.V, lift.F)
    with pytest.raises(msdeform.InvalidInput, match="no fixed or handle vertex"):
        msdeform.detail_distortion(lift.V, lift.V, lift.F, np.ones(len(lift.V), np.int32))
    # Fifth break test: refused only by prepare(), and in C++ or unclear words.
    with pytest.raises(msdeform.InvalidInput, match="lattice: the least-norm regularization must be positive"):
        msdeform.Deformer("lattice", regularization=-1.0)
    with pytest.raises(msdeform.InvalidInput, match="cage-mvc: the least-norm regularization must be positive"):
        msdeform.Deformer("cage-mvc", regularization=float("nan"))
    with pytest.raises(msdeform.InvalidInput, match="detail_distortion: there are no faces"):
        msdeform.detail_distortion(lift.V, lift.V, None, lift.labels)
    with pytest.raises(msdeform.InvalidInput, match=r"propagate: transfer\("):
        msdeform.Deformer("propagate", transfer=lambda s: 2.0).prepare(lift.V, lift.F, lift.labels)


def test_write_sel_refuses_a_skipped_handle_code(tmp_path):
    # Third break test: codes 0, 1, 3 were written, and every reader refused the file.
    with pytest.raises(msdeform.InvalidInput, match="handle 0 .selection code 2. has no vertex"):
        msdeform.write_sel(tmp_path / "gap.sel", np.array([0, 1, 3], np.int32))
    assert not (tmp_path / "gap.sel").exists()


def test_sel_round_trip(tmp_path, lift):
    path = tmp_path / "plane.sel"
    msdeform.write_sel(path, lift.labels)
    labels = msdeform.read_sel(path, len(lift.V))
    assert labels.dtype == np.int32
    np.testing.assert_array_equal(labels, lift.labels)


def test_read_sel_names_the_count_mismatch(tmp_path, lift):
    path = tmp_path / "plane.sel"
    msdeform.write_sel(path, lift.labels)
    n = len(lift.V)
    with pytest.raises(ValueError, match=f"{n} labels but the mesh has {n + 1} vertices") as info:
        msdeform.read_sel(path, n + 1)
    assert isinstance(info.value, msdeform.InvalidInput)
    assert "plane.sel" in str(info.value)


def test_def_round_trip_is_exact(tmp_path):
    T = [msdeform.rotation((1, 2, 3), 37.5, about=(0.1, 0.2, 0.3)) @ msdeform.translation((0.5, -1 / 3, 2)),
         msdeform.scaling(1.25)]
    path = tmp_path / "two.def"
    msdeform.write_def(path, T)
    back = msdeform.read_def(path)
    assert isinstance(back, list) and len(back) == 2
    for a, b in zip(back, T):
        assert a.shape == (4, 4) and a.dtype == np.float64
        np.testing.assert_array_equal(a, b)  # 17 significant digits
    msdeform.write_def(path, np.stack(T))  # an (H, 4, 4) array is accepted too
    np.testing.assert_array_equal(np.stack(msdeform.read_def(path)), np.stack(T))


def test_read_def_refuses_a_matrix_that_is_not_affine(tmp_path):
    path = tmp_path / "bad.def"
    path.write_text("1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 1 1\n")
    with pytest.raises(ValueError, match="0 0 0 1"):
        msdeform.read_def(path)
    # ... and write_def does not write one (nor a NaN), so every file it writes reads back.
    with pytest.raises(ValueError, match="matrix 0 is not affine"):
        msdeform.write_def(tmp_path / "ones.def", np.ones((4, 4)))
    nan = np.eye(4)
    nan[0, 3] = np.nan
    with pytest.raises(ValueError, match="matrix 0 has a non-finite entry"):
        msdeform.write_def(tmp_path / "nan.def", nan)
    # No transforms at all: read_def refuses such a file, so write_def does not write it (it did).
    with pytest.raises(ValueError, match="no transforms to write"):
        msdeform.write_def(tmp_path / "none.def", [])
    assert not (tmp_path / "ones.def").exists() and not (tmp_path / "nan.def").exists()
    assert not (tmp_path / "none.def").exists()


def test_dmat_groups_are_free_and_handles(tmp_path):
    path = tmp_path / "groups.dmat"
    path.write_text("1 5\n-1\n0\n0\n-1\n1\n")
    np.testing.assert_array_equal(msdeform.read_dmat_groups(path, 5), [1, 2, 2, 1, 3])


def test_missing_files_raise_file_not_found(tmp_path, lift):
    missing = tmp_path / "missing.off"
    for read in (msdeform.read_mesh, msdeform.read_soup, msdeform.read_def,
                 lambda p: msdeform.read_sel(p, 3), lambda p: msdeform.read_dmat_groups(p, 3),
                 msdeform.load_edit):
        with pytest.raises(FileNotFoundError) as info:
            read(missing)
        assert info.value.filename == str(missing)
    with pytest.raises(FileNotFoundError):
        msdeform.write_mesh(tmp_path / "no-such-folder" / "x.off", lift.V, lift.F)
    with pytest.raises(IsADirectoryError):
        msdeform.write_mesh(tmp_path, lift.V, lift.F)


def test_unknown_extension_and_bad_path_type(tmp_path, lift):
    with pytest.raises(ValueError, match=r"\.xyz"):
        msdeform.write_mesh(tmp_path / "x.xyz", lift.V, lift.F)
    with pytest.raises(TypeError, match="path"):
        msdeform.read_mesh(42)


def test_load_edit_reads_mesh_region_and_transforms(tmp_path, lift):
    msdeform.write_mesh(tmp_path / "e.off", lift.V, lift.F)
    msdeform.write_sel(tmp_path / "e.sel", lift.labels)
    msdeform.write_def(tmp_path / "e.def", lift.transforms)
    edit = msdeform.load_edit(tmp_path / "e.off", tmp_path / "e.sel", tmp_path / "e.def")
    V, F, labels, transforms = edit
    np.testing.assert_array_equal(V, lift.V)
    np.testing.assert_array_equal(F, lift.F)
    np.testing.assert_array_equal(labels, lift.labels)
    np.testing.assert_array_equal(transforms[0], lift.transforms[0])
    assert edit.name == "e" and edit.surface_problem is None and edit.control is None
    bare = msdeform.load_edit(tmp_path / "e.off")
    assert bare.labels is None and bare.transforms == []


def test_scenes(lift):
    assert set(msdeform.scene_names()) >= {"lift", "bend120", "twist135", "bar-lift", "bar-bend120", "bar-twist135"}
    V, F, labels, transforms = lift
    assert V.dtype == np.float64 and V.shape[1] == 3 and F.dtype == np.int32 and labels.dtype == np.int32
    assert set(np.unique(labels)) == {0, 1, 2}
    assert len(transforms) == 1
    np.testing.assert_allclose(transforms[0], msdeform.translation((0, 0, 0.3)), atol=1e-15)
    assert isinstance(lift.control, msdeform.ControlMesh) and lift.control.V.shape[0] < len(V)
    assert msdeform.scene("lift", "1k").V.shape == V.shape
    with pytest.raises(ValueError, match="unknown scene 'nope'.*bend120"):
        msdeform.scene("nope")
    with pytest.raises(TypeError, match="resolution"):
        msdeform.scene("lift", 1000.5)
    # An Edit indexes like the tuple it unpacks to; a huge int or no name is refused in words (they raised
    # pybind11's cast errors).
    assert lift[0] is lift.V and lift[3] is lift.transforms and len(lift) == 4
    assert lift == tuple(lift) and lift != (lift.V, lift.F, lift.labels, [])
    with pytest.raises(ValueError, match="resolution '9223372036854775808': expected a vertex count"):
        msdeform.scene("lift", 2**63)
    with pytest.raises(ValueError, match="resolution -1 is out of range"):  # as 0 and 15 are said
        msdeform.scene("lift", -1)
    with pytest.raises(TypeError, match="scene name must be a string"):
        msdeform.scene(None)


def test_transform_helpers_refuse_non_finite_values():
    # rotation('x', nan) returned a NaN matrix; deform refused it only later.
    with pytest.raises(ValueError, match="degrees must be finite"):
        msdeform.rotation("x", float("nan"))
    with pytest.raises(ValueError, match="factor must be finite"):
        msdeform.scaling(float("inf"))
    with pytest.raises(ValueError, match="t must be finite"):
        msdeform.translation((0, float("nan"), 0))
    # Huge and tiny axes are directions too (a huge one gave the identity, a tiny one "axis must not be zero").
    for axis in ((1e308, 1e308, 0), (1e-200, 1e-200, 0)):
        np.testing.assert_allclose(msdeform.rotation(axis, 90), msdeform.rotation((1, 1, 0), 90), atol=1e-15)
    with pytest.raises(ValueError, match="too far out"):
        msdeform.scaling(3, about=(1e308, 0, 0))
    # A zero factor is refused as --scale 0 is (third break test: a singular matrix, deformed with a warning).
    with pytest.raises(ValueError, match="a scale factor is zero"):
        msdeform.scaling((1, 0, 1))


def test_messages_use_the_python_names(tmp_path, lift):
    # Third break test: read_mesh's errors began "load_mesh:", and a warning advised load_mesh.
    path = tmp_path / "cloud.ply"
    msdeform.write_mesh(path, lift.V)
    with pytest.raises(ValueError, match="^read_mesh: .*a point cloud is not a mesh") as info:
        msdeform.read_mesh(path)
    assert "load_" not in str(info.value)
    F = lift.F.copy()
    F[5] = F[5, ::-1]
    with pytest.warns(msdeform.MsdeformWarning, match=r"loading the mesh with read_mesh does"):
        msdeform.Deformer("shell").prepare(lift.V, F, lift.labels)
