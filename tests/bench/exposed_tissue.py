#!/usr/bin/python3
"""Exposed inner tissue of label grids: the measure of a tear in a posed phantom.

    tests/bench/exposed_tissue.py ORGANS GRID [GRID ...] [--json OUT.json] [--by-axis]

Counts the voxel faces between background (label 0) and a voxel of a label
that is not skin (organ names starting with "Skin") and has no skin voxel
within one voxel (its 3 x 3 x 3 neighbourhood), so a skin layer that the
resampling thinned does not count; a posed grid whose count exceeds the rest
grid's shows tissue torn open. The first GRID is taken as the reference and
each other one is given as a change from it.

Needs numpy, nibabel and scipy (Debian: python3-numpy python3-nibabel python3-scipy).
"""

import argparse
import json
import sys

import nibabel as nib
import numpy as np
from scipy import ndimage


def skin_labels(organs_path):
    labels = []
    with open(organs_path, encoding="latin-1") as f:
        for line in f:
            tok = line.split()
            if len(tok) >= 4 and tok[0].isdigit() and " ".join(tok[1:-2]).lower().startswith("skin"):
                labels.append(int(tok[0]))
    return labels


def exposure(labels, skin):
    """Exposed faces per axis (x, y, z of the array), the bare voxels (inner
    tissue with such a face) and the skin voxels."""
    is_skin = np.isin(labels, skin)
    near_skin = ndimage.binary_dilation(is_skin, structure=np.ones((3, 3, 3), bool))
    inner = (labels != 0) & ~near_skin
    background = labels == 0
    per_axis = []
    bare = np.zeros_like(inner)
    for axis in range(3):
        a = np.moveaxis(inner, axis, 0)
        b = np.moveaxis(background, axis, 0)
        e = np.moveaxis(bare, axis, 0)
        low = a[1:] & b[:-1]   # background below along the axis
        high = a[:-1] & b[1:]  # background above
        e[1:] |= low
        e[:-1] |= high
        # Faces on the grid's boundary: the outside is background.
        e[0] |= a[0]
        e[-1] |= a[-1]
        per_axis.append(int(np.count_nonzero(low) + np.count_nonzero(high) + np.count_nonzero(a[0]) + np.count_nonzero(a[-1])))
    return per_axis, int(np.count_nonzero(bare)), int(np.count_nonzero(is_skin))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0], formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("organs", help="organ table (ID name tissue density)")
    ap.add_argument("grids", nargs="+", help="label grids; the first is the reference (the rest grid)")
    ap.add_argument("--json", metavar="OUT")
    ap.add_argument("--by-axis", action="store_true",
                    help="also the faces per axis (a limb turned across anisotropic slices opens the z faces) and "
                         "the bare voxels against the skin's: what a closed skin would need")
    args = ap.parse_args()
    skin = skin_labels(args.organs)
    if not skin:
        raise SystemExit(f"{args.organs}: no organ named Skin...")
    rows = []
    for path in args.grids:
        data = np.asarray(nib.load(path).dataobj)
        per_axis, bare, skin_voxels = exposure(data, skin)
        rows.append({"grid": path, "exposed_faces": sum(per_axis), "faces_xyz": per_axis, "bare_voxels": bare,
                     "skin_voxels": skin_voxels})
    ref = rows[0]["exposed_faces"]
    for r in rows:
        r["change_pct"] = 100.0 * (r["exposed_faces"] - ref) / ref if ref else float("nan")
        print(f"{r['grid']}: {r['exposed_faces']} exposed inner-tissue faces ({r['change_pct']:+.2f} % against {rows[0]['grid']})")
        if args.by_axis:
            x, y, z = r["faces_xyz"]
            print(f"  faces x {x}, y {y}, z {z}; {r['bare_voxels']} bare voxels, {r['skin_voxels']} skin voxels "
                  f"({100.0 * r['bare_voxels'] / max(r['skin_voxels'], 1):.1f} %)")
    if args.json:
        with open(args.json, "w") as f:
            json.dump(rows, f, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
