"""Shared fixtures of msdeform's pytest suite. Run with Debian's interpreter (it has numpy):

    PYTHONPATH=build/python /usr/bin/python3 -m pytest -q python/tests

MSD_SHARED_DATA names the folder with the 2008 survey's meshes (survey/); without it the tests look
for ../shared/data beside the repository and skip the survey tests when it is missing."""

import os
import pathlib

import numpy as np
import pytest

import msdeform

# The bumpy plane at about this many vertices: small enough for every method (PriMo included) to
# prepare and deform in well under a second each.
RESOLUTION = 1000


@pytest.fixture(scope="session")
def lift():
    """The built-in 'lift' edit of the bumpy plane: fixed x < 0.2, one handle x > 0.8 raised by 0.3."""
    return msdeform.scene("lift", RESOLUTION)


@pytest.fixture(scope="session")
def bend():
    """The built-in 'bend120' edit of the bumpy plane (a rotation of the handle, not only a translation)."""
    return msdeform.scene("bend120", RESOLUTION)


@pytest.fixture(scope="session")
def survey_dir():
    root = os.environ.get("MSD_SHARED_DATA")
    if root:
        where = "MSD_SHARED_DATA"
    else:
        root = str(pathlib.Path(__file__).resolve().parents[3] / "shared" / "data")
        where = "the default (no MSD_SHARED_DATA)"
    survey = pathlib.Path(root) / "survey"
    if not (survey / "cylinder.off").is_file():
        pytest.skip(f"the survey meshes are not at {survey} ({where}); set MSD_SHARED_DATA to the folder holding survey/")
    return survey


def diagonal(V):
    V = np.asarray(V)
    return float(np.linalg.norm(V.max(axis=0) - V.min(axis=0)))
