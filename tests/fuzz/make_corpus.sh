#!/usr/bin/env bash
# Regenerates the seed corpus in tests/fuzz/corpus/: small valid files of
# every format each harness reads, from voxmorph's writers (a release build)
# and meshio for the encodings voxmorph does not write (VTU ascii/binary,
# Gmsh binary, binary PLY). Usage: tests/fuzz/make_corpus.sh [voxmorph binary]
set -euo pipefail
cd "$(dirname "$0")"
bin=$(realpath "${1:-../../build/release/voxmorph}")
out=corpus
rm -rf "$out"
mkdir -p "$out"/{nifti,sizing_grid,metaimage,nrrd,inr,medit,meshb,vtu,gmsh,obj,off,ply,pose,organs,remesh,mesh,parts,viewer_script,prepared}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

"$bin" synth stick --size 8 -o "$tmp/g.nii" --organs "$out/organs/stick.dat" >/dev/null
cp ../../assets/icrp110_am_media.dat "$out/organs/media.dat"
head -c 2000 ../../assets/icrp110_am_organs.dat > "$out/organs/am_head.dat"
"$bin" synth spheres --size 8 -o "$tmp/s.nii.gz" >/dev/null
cp "$tmp/g.nii" "$out/nifti/stick.nii"
cp "$tmp/s.nii.gz" "$out/nifti/spheres.nii.gz"
# Sizing grids (mm values, fuzz_sizing_grid): float32 in a mirrored sform,
# int16 scaled by scl_slope / scl_inter in a qform (gzip), uint8 in pixdim
# only; and a label grid, which is one too.
/usr/bin/python3 - "$out/sizing_grid" <<'PY'
import sys, nibabel as nib, numpy as np
out = sys.argv[1]
ramp = np.linspace(1.5, 6.0, 60, dtype=np.float32).reshape((5, 4, 3), order="F")
img = nib.Nifti1Image(ramp, np.diag([-4.0, 4.0, 4.0, 1.0]) + np.array([[0, 0, 0, 18], [0] * 4, [0] * 4, [0] * 4]))
img.to_filename(out + "/float32_sform.nii")
img = nib.Nifti1Image(np.arange(24, dtype=np.int16).reshape((4, 3, 2), order="F"), None)
img.set_qform(np.diag([2.0, 2.0, 3.0, 1.0]), code=1)
img.set_sform(None, code=0)
img.header.set_slope_inter(0.25, 1.0)
img.to_filename(out + "/int16_scaled_qform.nii.gz")
img = nib.Nifti1Image(np.full((3, 3, 3), 2, np.uint8), None)
img.header.set_zooms((10, 10, 10))
img.set_qform(None, code=0)
img.set_sform(None, code=0)
img.to_filename(out + "/uint8_pixdim.nii")
PY
cp "$tmp/g.nii" "$out/sizing_grid/stick_labels.nii"
for f in stick.mha stick.mhd; do "$bin" synth stick --size 8 -o "$tmp/$f" >/dev/null; done
cp "$tmp/stick.mha" "$out/metaimage/stick.mha"
/usr/bin/python3 - "$tmp/stick.mhd" "$out/metaimage/stick_raw.mha" <<'PY'
import sys, re
hdr = open(sys.argv[1]).read()
raw_name = re.search(r"ElementDataFile = (.*)", hdr).group(1).strip()
raw = open(sys.argv[1].rsplit('/', 1)[0] + '/' + raw_name, 'rb').read()
data = raw
hdr = re.sub(r"ElementDataFile = .*", "ElementDataFile = LOCAL", hdr)
open(sys.argv[2], 'wb').write(hdr.encode() + data)
PY
"$bin" synth stick --size 8 -o "$out/nrrd/stick_gzip.nrrd" >/dev/null
printf 'NRRD0004\ntype: uint8\ndimension: 3\nsizes: 2 2 2\nspacings: 1 1 1\nendian: little\nencoding: raw\n\n\0\1\1\2\0\1\1\2' > "$out/nrrd/raw.nrrd"
"$bin" synth stick --size 8 -o "$out/inr/stick.inr" >/dev/null
"$bin" synth stick --size 8 -o "$out/inr/stick.inr.gz" >/dev/null

"$bin" mesh "$tmp/s.nii.gz" -l 6 -o "$out/medit/spheres.mesh" -q >/dev/null
"$bin" mesh "$tmp/s.nii.gz" -l 6 -o "$out/meshb/spheres.meshb" -q >/dev/null
# Meshes that are not an embedding (issue 40): seeds of the Medit reader and
# the remesher, and the cases of tests/geometry/remesh/remesh_bad_topology_test.cpp.
"$bin" synth spheres --size 12 -o "$tmp/s12.nii.gz" >/dev/null
"$bin" mesh "$tmp/s12.nii.gz" -l 6 -o "$out/remesh/spheres12.mesh" -q >/dev/null
cp "$out/medit/spheres.mesh" "$out/remesh/spheres.mesh"
/usr/bin/python3 make_bad_topology.py "$out/remesh/spheres12.mesh" "$out/medit" "$out/remesh"
# Tiny grids for the mesh path: dimensions - 1, target length - 1, labels (x fastest).
/usr/bin/python3 - "$out/mesh" <<'PY'
import sys
out = sys.argv[1]
def grid(name, nx, ny, nz, length, label):
    cells = [label(i, j, k) for k in range(nz) for j in range(ny) for i in range(nx)]
    open(out + "/" + name, "wb").write(bytes([nx - 1, ny - 1, nz - 1, length - 1] + cells))
grid("one_voxel", 1, 1, 1, 1, lambda i, j, k: 1)
grid("two_labels", 4, 3, 2, 1, lambda i, j, k: 1 if i < 2 else 2)
grid("nested", 6, 6, 6, 2, lambda i, j, k: 2 if 2 <= i <= 3 and 2 <= j <= 3 and 2 <= k <= 3 else (1 if 1 <= min(i, j, k) and max(i, j, k) <= 4 else 0))
grid("corner_contact", 4, 4, 4, 1, lambda i, j, k: 1 if max(i, j, k) < 2 else (3 if min(i, j, k) >= 2 else 0))
grid("edge_contact", 4, 4, 2, 1, lambda i, j, k: 1 if i < 2 and j < 2 else (2 if i >= 2 and j >= 2 else 0))
grid("three_junction", 5, 5, 3, 2, lambda i, j, k: [1, 2, 3][(i >= 2) + (j >= 3)] if k < 2 else 0)
PY
"$bin" mesh "$tmp/s.nii.gz" -l 6 -o "$out/vtu/spheres.vtu" -q >/dev/null
"$bin" mesh "$tmp/s.nii.gz" -l 6 -o "$out/gmsh/spheres.msh" -q >/dev/null
/usr/bin/python3 - "$out" <<'PY'
import sys, meshio, numpy as np
out = sys.argv[1]
points = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 1]], dtype=float)
tets = np.array([[0, 1, 2, 3], [1, 2, 3, 4]])
m = meshio.Mesh(points, [("tetra", tets)], cell_data={"label": [np.array([1, 2], dtype=np.int32)]})
meshio.vtu.write(out + "/vtu/two_ascii.vtu", m, binary=False)
meshio.vtu.write(out + "/vtu/two_zlib.vtu", m, binary=True, compression="zlib")
meshio.vtu.write(out + "/vtu/two_raw.vtu", m, binary=True, compression=None)
g = meshio.Mesh(points, [("tetra", tets)], cell_data={"gmsh:physical": [np.array([1, 2])], "gmsh:geometrical": [np.array([1, 2])]})
meshio.gmsh.write(out + "/gmsh/two_ascii.msh", g, fmt_version="4.1", binary=False)
meshio.gmsh.write(out + "/gmsh/two_binary.msh", g, fmt_version="4.1", binary=True)
tri = meshio.Mesh(points[:4], [("triangle", np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]))])
meshio.ply.write(out + "/ply/tet_binary.ply", tri, binary=True)
meshio.ply.write(out + "/ply/tet_ascii.ply", tri, binary=False)
PY
"$bin" cage "$tmp/g.nii" -o "$out/obj/cage.obj" --vertices 12 >/dev/null
"$bin" cage "$tmp/g.nii" -o "$out/off/cage.off" --vertices 12 >/dev/null
"$bin" cage "$tmp/g.nii" -o "$out/ply/cage.ply" --vertices 12 >/dev/null
printf 'v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nvt 0 0\nf 1/1 3/1 2/1\nf 1//1 2//1 4//1\nf -4 -1 -2\nf 2 3 4\n' > "$out/obj/tet.obj"
printf 'OFF\n4 4 6\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n' > "$out/off/tet.off"
cp ../../assets/poses/*.json "$out/pose/"
printf '{"selections": [{"name": "all", "sphere": {"center": [0, 0, 0], "radius": 5}, "transform": {"rotation": {"axis": [0, 0, 1], "angle_deg": 10, "center": [0, 0, 0]}, "translation": [1, 2, 3]}}]}' > "$out/pose/sphere.json"
# Joint poses for fuzz_joint_pose (compiled against the skeleton figure):
# the shipped ones (the hard postures among them), and the overrides of joint_options,
# a joint centre and an axis.
cp ../../assets/poses/*_joints.json "$out/joint_pose/"
# The figure's joints: right_shoulder, right_elbow, right_wrist, right_hip,
# left_hip, left_knee.
printf '{"joints": {"right_shoulder": {"flexion": 90, "abduction": 30, "rotation": 20}, "right_elbow": {"flexion": 120}, "right_wrist": {"flexion": 30, "abduction": 10}}}' > "$out/joint_pose/figure_arm.json"
printf '{"joints": {"right_hip": {"flexion": 90}, "left_hip": {"flexion": 90}, "left_knee": {"flexion": 90}}}' > "$out/joint_pose/figure_seated.json"
printf '{"joints": {"right_shoulder": {"flexion": 30, "abduction": 20, "center": [10, 0, 60]}, "right_elbow": {"flexion": 90, "axis": [1, 0, 0.2]}}, "joint_options": {"zone": "free", "margin_mm": 20, "groups": "organs"}}' > "$out/joint_pose/overrides.json"
printf '{"joints": {"left_hip": {"flexion": 45}, "left_knee": {"flexion": 60}}, "joint_options": {"zone": "child"}, "selections": [{"name": "hand", "body_parts": ["right_hand"], "transform": {"translation": [0, 5, 0]}}]}' > "$out/joint_pose/leg_and_parts.json"
# Body-part grids of the skeleton figure fuzz_parts checks against (size 24),
# and of a smaller figure (other dims).
"$bin" synth skeleton --size 24 -o "$tmp/sk24.nii" --organs "$tmp/sk24.dat" >/dev/null
"$bin" parts "$tmp/sk24.nii" --organs "$tmp/sk24.dat" -o "$out/parts/skeleton24_parts.nii" -q
"$bin" synth skeleton --size 20 -o "$tmp/sk20.nii" --organs "$tmp/sk20.dat" >/dev/null
"$bin" parts "$tmp/sk20.nii" --organs "$tmp/sk20.dat" -o "$out/parts/other_dims.nii" -q
cp ../app/data/viewer_session.json "$out/viewer_script/session.json"
cp ../app/data/viewer_articulated_session.json "$out/viewer_script/articulated_session.json"
# Prepared states (fuzz_prepared): the stick figure without a skeleton, the
# skeleton figure with its skeleton and a separated arm, and one with the
# articulated transfer mesh.
"$bin" synth stick --size 16 -o "$tmp/st16.nii" >/dev/null
"$bin" prepare "$tmp/st16.nii" --vertices 12 -o "$out/prepared/stick16.vxprep" -q
printf '{"joints": {"right_shoulder": {"abduction": 30}}}' > "$tmp/arm.json"
"$bin" prepare "$tmp/sk24.nii" --organs "$tmp/sk24.dat" --pose "$tmp/arm.json" --vertices 24 -o "$out/prepared/skeleton24.vxprep" -q
# ... and a larger one with its articulated transfer mesh (two articular bodies).
"$bin" synth skeleton --size 32 -o "$tmp/sk32.nii" --organs "$tmp/sk32.dat" >/dev/null
"$bin" prepare "$tmp/sk32.nii" --organs "$tmp/sk32.dat" --articulated --vertices 24 -o "$out/prepared/skeleton32_articulated.vxprep" -q
find "$out" -type f | sort | xargs wc -c | tail -1
