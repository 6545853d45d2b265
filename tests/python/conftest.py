"""Fixtures of the voxmorph module's tests: the CLI, the assets and small inputs.

ctest runs pytest with PYTHONPATH holding the built module and
VOXMORPH_BINARY / VOXMORPH_SOURCE naming the CLI and the source tree.
"""

import os
import subprocess

import nibabel as nib
import numpy as np
import pytest

SOURCE = os.environ.get("VOXMORPH_SOURCE", os.path.join(os.path.dirname(__file__), "..", ".."))
BINARY = os.environ.get("VOXMORPH_BINARY", os.path.join(SOURCE, "build", "release", "voxmorph"))
AM = os.path.join(SOURCE, "assets", "icrp110_am.nii.gz")
AM_ORGANS = os.path.join(SOURCE, "assets", "icrp110_am_organs.dat")


def cli(*args, cwd=None):
    """Runs the voxmorph CLI; returns the completed process (check=True)."""
    return subprocess.run([BINARY, *args], cwd=cwd, check=True, capture_output=True, text=True)


@pytest.fixture(scope="session")
def am_image():
    return nib.load(AM)


@pytest.fixture(scope="session")
def am_crop(am_image):
    """A region of the ICRP 110 adult male (95 x 90 x 10 voxels through the trunk) and its affine."""
    data = np.asarray(am_image.dataobj)[80:175, 30:120, 148:158]
    affine = am_image.affine.copy()
    affine[:3, 3] = am_image.affine[:3, :3] @ [80, 30, 148] + am_image.affine[:3, 3]
    return data, affine


@pytest.fixture(scope="session")
def figure(tmp_path_factory):
    """The synthetic skeleton figure (bones named as in the ICRP tables) with its organ table and a joint pose."""
    d = tmp_path_factory.mktemp("figure")
    cli("synth", "skeleton", "--size", "96", "-o", str(d / "figure.nii.gz"), "--organs", str(d / "figure.dat"))
    pose = d / "pose.json"
    pose.write_text('{"joints": {"right_shoulder": {"abduction": 30}, "right_elbow": {"flexion": 40}}}')
    return {"grid": str(d / "figure.nii.gz"), "organs": str(d / "figure.dat"), "pose": str(pose), "dir": d}
