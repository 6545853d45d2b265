#!/usr/bin/python3
"""Exposed inner tissue of label grids: the measure of a tear in a posed phantom.

    tests/bench/exposed_tissue.py ORGANS GRID [GRID ...] [--json OUT.json]

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


def exposed_faces(labels, skin):
    is_skin = np.isin(labels, skin)
    near_skin = ndimage.binary_dilation(is_skin, structure=np.ones((3, 3, 3), bool))
    inner = (labels != 0) & ~near_skin
    background = labels == 0
    faces = 0
    for axis in range(3):
        a = np.moveaxis(inner, axis, 0)
        b = np.moveaxis(background, axis, 0)
        faces += np.count_nonzero(a[1:] & b[:-1]) + np.count_nonzero(a[:-1] & b[1:])
        # Faces on the grid's boundary: the outside is background.
        faces += np.count_nonzero(a[0]) + np.count_nonzero(a[-1])
    return int(faces)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0], formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("organs", help="organ table (ID name tissue density)")
    ap.add_argument("grids", nargs="+", help="label grids; the first is the reference (the rest grid)")
    ap.add_argument("--json", metavar="OUT")
    args = ap.parse_args()
    skin = skin_labels(args.organs)
    if not skin:
        raise SystemExit(f"{args.organs}: no organ named Skin...")
    rows = []
    for path in args.grids:
        data = np.asarray(nib.load(path).dataobj)
        rows.append({"grid": path, "exposed_faces": exposed_faces(data, skin)})
    ref = rows[0]["exposed_faces"]
    for r in rows:
        r["change_pct"] = 100.0 * (r["exposed_faces"] - ref) / ref if ref else float("nan")
        print(f"{r['grid']}: {r['exposed_faces']} exposed inner-tissue faces ({r['change_pct']:+.2f} % against {rows[0]['grid']})")
    if args.json:
        with open(args.json, "w") as f:
            json.dump(rows, f, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
