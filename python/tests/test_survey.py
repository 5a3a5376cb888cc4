"""A real edit: the survey's cylinder (Botsch & Sorkine 2008, 4802 vertices, its .sel and .def), bent
by shell and ARAP; the handle must reach its target."""

import numpy as np
import pytest

import msdeform

from conftest import diagonal


@pytest.mark.parametrize("name", ["shell", "arap"])
def test_cylinder_edit_reaches_its_target(name, survey_dir):
    edit = msdeform.load_edit(survey_dir / "cylinder.off", survey_dir / "cylinder.sel", survey_dir / "cylinder.def")
    V, F, labels, transforms = edit
    assert V.shape == (4802, 3) and len(transforms) == 1 and edit.surface_problem is None
    d = msdeform.Deformer(name)
    d.prepare(V, F, labels)
    out = d.deform(transforms)
    handle = labels == 2
    target = V[handle] @ transforms[0][:3, :3].T + transforms[0][:3, 3]
    travel = np.linalg.norm(target - V[handle], axis=1).max()
    assert travel > 0.2 * diagonal(V)  # a large edit
    assert np.abs(out[handle] - target).max() <= 1e-8 * diagonal(V)
    assert msdeform.handle_error(V, out, labels, transforms) <= 1e-8 * diagonal(V)
    if name == "arap":
        assert d.frame_report.converged
        # ARAP bends the tube nearly rigidly; the linear shell does not preserve rotations.
        shell = msdeform.Deformer("shell")
        shell.prepare(V, F, labels)
        assert (msdeform.rigidity_error(V, out, F).stats.mean
                < msdeform.rigidity_error(V, shell.deform(transforms), F).stats.mean)
