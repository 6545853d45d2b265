"""voxmorph: segmented volumes from numpy (type stubs of the compiled module; docs/PYTHON.md)."""

from os import PathLike
from typing import Any, Literal, Sequence, Union

import numpy as np
import numpy.typing as npt

__version__: str

_Path = Union[str, PathLike[str]]
_Pose = Union[dict[str, Any], _Path]
_Organs = Union["OrganTable", _Path, None]

class OrganTable:
    """Label -> organ name, tissue number and density (g/cm^3), read from an ICRP 110 style "organs.dat"."""

    path: str
    def __init__(self, path: _Path) -> None:
        """Reads an organ table; ValueError naming the file and line when malformed, FileNotFoundError when missing."""
    def __len__(self) -> int: ...
    def __contains__(self, id: int) -> bool: ...
    def __getitem__(self, id: int) -> dict[str, Any]:
        """{'id', 'name', 'tissue', 'density_g_cm3'} of a label; KeyError when absent."""
    @property
    def names(self) -> dict[int, str]:
        """Organ names by label."""

class Grid:
    """Labels (uint16) on a voxel grid with spacing (mm) and a voxel-to-world affine (nibabel's, RAS mm)."""

    source: str
    def __init__(
        self,
        labels: npt.ArrayLike,
        spacing: Sequence[float] | None = None,
        affine: npt.ArrayLike | None = None,
    ) -> None:
        """labels: 3-D integer array indexed [i, j, k]; a uint16 array in Fortran order is the grid's storage
        (borrowed and kept alive, not copied), any other is copied once (widened to uint16) into the grid;
        spacing: voxel size in mm (default the affine's, else 1); affine: 4 x 4 voxel-to-world matrix."""
    @staticmethod
    def zeros(
        shape: tuple[int, int, int],
        spacing: Sequence[float] | None = None,
        affine: npt.ArrayLike | None = None,
    ) -> Grid:
        """A grid of label 0, to fill in place through .labels (no intermediate array)."""
    @staticmethod
    def read(path: _Path) -> Grid:
        """Reads .nii, .nii.gz, .mha, .mhd, .nrrd, .nhdr or .inr; ValueError for corrupt files, OSError for unreadable ones."""
    def write(self, path: _Path) -> None:
        """Writes the grid (format from the extension), atomically."""
    @property
    def labels(self) -> npt.NDArray[np.uint16]:
        """(nx, ny, nz) view of the grid's storage (its own, or the array it borrows), Fortran order: no copy;
        writes go to the grid; read-only when the borrowed array is."""
    @property
    def affine(self) -> npt.NDArray[np.float64]:
        """4 x 4 voxel-to-world matrix (mm, RAS)."""
    @property
    def spacing(self) -> tuple[float, float, float]: ...
    @property
    def shape(self) -> tuple[int, int, int]: ...
    def statistics(self, organs: _Organs = None) -> dict[str, list[Any]]:
        """Columns label, [name], voxels, volume_mm3, [density_g_cm3, mass_g] (a dict pandas.DataFrame takes)."""

def deform(
    grid: Grid | _Path,
    pose: _Pose,
    *,
    organs: _Organs = None,
    preserve_volumes: bool | Literal["deformed", "rest"] = False,
    skin_cover: bool = True,
    prepared: str | PathLike[str] | None = None,
    output: str = "",
    cpu: bool = False,
    samples: int = 1,
    rigid_bones: bool = False,
    articulated: bool = False,
    bone_gap: float = 10.0,
    force: bool = False,
    max_body_change: float = 2.0,
    max_bone_change: float = 10.0,
    max_bone_overlap: float = 2.0,
    max_tissue_overlap: float = 0.5,
    allow_growth: bool = False,
    max_memory: int = 0,
) -> tuple[Grid, dict[str, Any]]:
    """Re-poses a grid as `voxmorph deform`: (posed Grid, the CLI's JSON report as a dict).
    prepared: a `voxmorph prepare` state (.vxprep) of the grid file given as `grid`; byte-identical results."""

class Posing:
    """The per-frame posing session: pipeline built once, each frame() is ARAP -> Green coordinates -> propagation."""

    def __init__(self, grid: Grid, pose: _Pose, organs: _Organs = None) -> None: ...
    def set_pose(self, pose: _Pose) -> None:
        """Replaces the selections with a pose's (joints compiled against the session's skeleton)."""
    def set_joints(self, joints: dict[str, dict[str, float]]) -> None:
        """Joint angles in degrees, e.g. {'right_shoulder': {'abduction': 60}}."""
    def frame(self) -> dict[str, Any]:
        """positions (#V x 3 world mm), label_volumes, inverted_tets, vertices_outside_cage,
        bones_through_each_other (what deform refuses the joint pose for, or None), deform_ms."""
    def rasterize(self, samples: int = 1, cpu: bool = False) -> Grid:
        """The posed full-resolution grid of the current pose."""
    @property
    def transfer_mesh(self) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.int32], npt.NDArray[np.int32]]:
        """The rest transfer mesh: points (#V x 3 world mm), tets (#T x 4), labels (#T)."""
    @property
    def pose(self) -> dict[str, Any]:
        """The current pose (grid frame), as a pose file holds it."""

def parts(grid: Grid, organs: _Organs, parts: Grid | None = None) -> tuple[Grid, list[dict[str, Any]]]:
    """(body-part Grid, joints) from the bones the organ table names, as `voxmorph parts`."""

_MeshResult = tuple[npt.NDArray[np.float64], npt.NDArray[np.int32], npt.NDArray[np.int32], dict[str, Any]]

def mesh(
    grid: Grid,
    l: float,
    *,
    organs: _Organs = None,
    iterations: int = 5,
    flip_smooth: int = 3,
    surface: Literal["hpss", "pss", "none"] = "hpss",
    keep_imaginary: bool = False,
    distances: bool = True,
    threads: int = 2,
) -> _MeshResult:
    """Meshes a label grid (M-MAd) at edge length l mm: (points world mm, tets, labels, quality report)."""

def remesh(
    points: npt.ArrayLike,
    tets: npt.ArrayLike,
    labels: npt.ArrayLike,
    l: float,
    *,
    organs: _Organs = None,
    iterations: int = 5,
    flip_smooth: int = 3,
    surface: Literal["hpss", "pss", "none"] = "hpss",
    keep_imaginary: bool = False,
    distances: bool = True,
    threads: int = 2,
) -> _MeshResult:
    """Remeshes a labeled tet mesh (M-MAd) at edge length l mm: (points, tets, labels, quality report)."""

def render(
    grid: Grid,
    *,
    pose: _Pose | None = None,
    organs: _Organs = None,
    camera: str = "",
    cuts: Sequence[str] = (),
    size: tuple[int, int] = (640, 480),
    hide: str = "",
    shading: Literal["smooth", "faces"] = "smooth",
    cpu: bool = False,
) -> npt.NDArray[np.uint8]:
    """Ray-casts the grid (posed through its transfer mesh with a pose): a (height, width, 3) uint8 RGB array."""
