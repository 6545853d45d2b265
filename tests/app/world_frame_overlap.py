"""Rotated LPS round trip: a label grid stored with a rotated, axis-flipped
affine is meshed by voxmorph; nibabel places the image and meshio the mesh,
and the mesh's labelled volume must lie over the image's labelled voxels.

  world_frame_overlap.py make GRID.nii.gz [mirrored]   writes the test grid
                                               (mirrored: one axis flipped)
  world_frame_overlap.py overlap GRID MESH     prints "overlap <fraction>"

The overlap is the fraction of labelled voxels whose centre (in world mm, by
nibabel's affine) lies in a mesh tet of the same label (meshio)."""
import sys

import meshio
import nibabel as nib
import numpy as np


def make(path, mirrored=False):
    n = 28
    ijk = np.indices((n, n, n)).astype(float)
    labels = np.zeros((n, n, n), np.uint8)
    # Two off-centre blocks and a ball: a wrong rotation or flip moves them.
    labels[4:20, 6:14, 5:24] = 1
    r = np.sqrt((ijk[0] - 17) ** 2 + (ijk[1] - 18) ** 2 + (ijk[2] - 12) ** 2)
    labels[r < 7] = 2
    labels[18:25, 3:9, 16:26] = 3
    # LPS storage: i runs to the Left, j to Posterior (x, y negated), then a
    # 30 degree turn about z and a tilt of 20 degrees about x; 1.5 x 1.2 x 2 mm.
    c, s = np.cos(np.radians(30)), np.sin(np.radians(30))
    rz = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])
    c, s = np.cos(np.radians(20)), np.sin(np.radians(20))
    rx = np.array([[1, 0, 0], [0, c, -s], [0, s, c]])
    affine = np.eye(4)
    flips = [-1.0, 1.0, 1.0] if mirrored else [-1.0, -1.0, 1.0]
    affine[:3, :3] = rz @ rx @ np.diag(flips) @ np.diag([1.5, 1.2, 2.0])
    affine[:3, 3] = [40.0, -25.0, 60.0]
    image = nib.Nifti1Image(labels, affine)
    image.set_qform(affine, code=1)
    image.set_sform(affine, code=1)
    nib.save(image, path)


def overlap(grid_path, mesh_path):
    image = nib.load(grid_path)
    labels = np.asarray(image.dataobj).astype(int)
    inverse = np.linalg.inv(image.affine)
    mesh = meshio.read(mesh_path)
    points = mesh.points
    tets = mesh.cells_dict["tetra"]
    tet_labels = mesh.cell_data_dict["label"]["tetra"]
    # Label of the tet holding each voxel centre (0: none).
    found = np.zeros(labels.shape, int)
    index_points = (inverse[:3, :3] @ points.T).T + inverse[:3, 3]
    for t, label in zip(tets, tet_labels):
        corners = points[t]
        lo = np.maximum(np.floor(index_points[t].min(axis=0)).astype(int), 0)
        hi = np.minimum(np.ceil(index_points[t].max(axis=0)).astype(int), np.array(labels.shape) - 1)
        if np.any(hi < lo):
            continue
        grid = np.stack(np.meshgrid(*[np.arange(lo[a], hi[a] + 1) for a in range(3)], indexing="ij"), -1).reshape(-1, 3)
        world = (image.affine[:3, :3] @ grid.T).T + image.affine[:3, 3]
        m = np.column_stack([corners[1] - corners[0], corners[2] - corners[0], corners[3] - corners[0]])
        b = np.linalg.solve(m, (world - corners[0]).T).T
        inside = (b >= -1e-9).all(axis=1) & (b.sum(axis=1) <= 1 + 1e-9)
        g = grid[inside]
        found[g[:, 0], g[:, 1], g[:, 2]] = label
    labelled = labels > 0
    agree = (found == labels) & labelled
    print("overlap %.4f of %d labelled voxels" % (agree.sum() / labelled.sum(), labelled.sum()))


if __name__ == "__main__":
    if sys.argv[1] == "make":
        make(sys.argv[2], len(sys.argv) > 3 and sys.argv[3] == "mirrored")
    else:
        overlap(sys.argv[2], sys.argv[3])
