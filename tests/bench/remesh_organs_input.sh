#!/usr/bin/env bash
# The five-organ CGAL Mesh_3 input of the remesher's peers
# (tests/bench/mmg3d_peer.sh, remesh_interface_bound.sh): five organs of the
# AM (gall bladder, kidneys, liver, pancreas, spleen; every other label
# cleared, cropped to them with a 2-voxel margin) as WORKDIR/organs.nii.gz,
# meshed by remesh_bench's exuded Mesh_3 (cells of about l, facets within
# l / 4) into WORKDIR/organs_mesh3.mesh, and its domain tets in
# WORKDIR/organs_input.mesh. Kept when already there.
# Usage: tests/bench/remesh_organs_input.sh WORKDIR [l]   (default l = 8 mm;
#   remesh_bench from VOX_BUILD, default build/release)
set -euo pipefail
cd "$(dirname "$0")/../.."
[ $# -ge 1 ] || { echo "usage: $0 WORKDIR [l]" >&2; exit 2; }
work=$1
l=${2:-8}
build=${VOX_BUILD:-build/release}
mkdir -p "$work"
if [ ! -f "$work/organs_input.mesh" ]; then
  /usr/bin/python3 - "$work/organs.nii.gz" <<'PY'
import nibabel as nib, numpy as np, sys
img = nib.load('assets/icrp110_am.nii.gz')
a = np.asarray(img.dataobj)
keep = np.isin(a, [70, 71, 89, 90, 91, 92, 93, 94, 95, 113, 127])
idx = np.argwhere(keep)
lo, hi = np.maximum(idx.min(0) - 2, 0), np.minimum(idx.max(0) + 3, a.shape)
crop = img.slicer[lo[0]:hi[0], lo[1]:hi[1], lo[2]:hi[2]]
labels = np.where(keep, a, 0)[lo[0]:hi[0], lo[1]:hi[1], lo[2]:hi[2]].astype(a.dtype)
out = nib.Nifti1Image(labels, crop.affine, crop.header)
nib.save(out, sys.argv[1])
PY
  VOX_REMESH_GRID="$work/organs.nii.gz" VOX_REMESH_L="$l" VOX_REMESH_INPUT=mesh3 \
    VOX_REMESH_MESH3_FILE="$work/organs_mesh3.mesh" "$build/bench/remesh_bench" --benchmark_filter=BM_PeerOutput \
    >/dev/null 2>&1 || true
  /usr/bin/python3 - "$work/organs_mesh3.mesh" "$work/organs_input.mesh" <<'PY'
import meshio, numpy as np, sys
m = meshio.read(sys.argv[1])
tets = m.cells_dict['tetra']
ref = m.cell_data_dict['medit:ref']['tetra']
keep = ref > 0
used = np.unique(tets[keep])
index = np.full(len(m.points), -1)
index[used] = np.arange(len(used))
meshio.write(sys.argv[2], meshio.Mesh(m.points[used], [('tetra', index[tets[keep]])],
                                      cell_data={'medit:ref': [ref[keep]]}))
PY
fi
