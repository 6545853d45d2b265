#!/usr/bin/python3
"""How exactly a posed grid carries its bones: each posed bone against its rest bone moved by its part's transform.

    tests/bench/bone_fidelity.py REST POSED ORGANS PARTS REPORT [--json OUT.json] [--min-dice D] [--max-volume-pct P]

REST and POSED are label grids (`voxmorph deform -o POSED --report REPORT`),
ORGANS the organ table, PARTS the body-part grid of REST (`voxmorph parts REST
--organs ORGANS -o PARTS`), REPORT the deformation's JSON report, whose
"part_transforms" give each body part's rest-to-posed 4 x 4 matrix in world mm.

Bones and sides as tests/bench/bone_shapes.py splits them. The reference of a
bone (per side) is its rest voxels moved by their parts' transforms and
resampled nearest neighbour on the posed grid's lattice: a posed voxel belongs
to it when the rest voxel holding its centre mapped back by the part's
inverse transform is one of the bone's voxels of that part. A posed voxel of
the bone's labels goes to the side whose reference is nearer. A segment the
report moves on its own (a scapula, a patella: "right_patella") moves its
bone's voxels by its own transform. Per bone and
side: Dice of the posed bone and the reference, and the posed volume against
the reference's. With --min-dice / --max-volume-pct the exit status is 1 when
a bone of at least 1000 rest voxels misses either bound (the bones are listed).

Needs numpy, nibabel and scipy (Debian: python3-numpy python3-nibabel python3-scipy).
"""

import argparse
import json
import os
import sys

import nibabel as nib
import numpy as np
from scipy import ndimage

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bone_shapes import ORDER, Grid, body_frame, classify_bone, read_organs, sides  # noqa: E402


def reference(rest, posed, rest_ijk, parts_at, transforms, own=None):
    """Posed-lattice mask of the rest voxels rest_ijk moved by their parts' transforms (nearest neighbour).

    own: a transform (4 x 4) that moves every voxel instead (a segment of its own, such as a scapula)."""
    if own is not None:
        parts_at = np.full(len(rest_ijk), -1)
    out = np.zeros(posed.data.shape, bool)
    inv_rest = np.linalg.inv(rest.affine)
    shape = np.array(rest.data.shape)
    for part in np.unique(parts_at):
        sel = rest_ijk[parts_at == part].astype(np.int64)
        if own is not None:
            m = np.asarray(own)
        elif part == 0 or part > len(transforms):
            raise SystemExit(f"bone voxels in body part {part}, which the report has no transform for")
        else:
            m = np.array(transforms[part - 1]["matrix"])
        member = np.zeros(rest.data.shape, bool)
        member[tuple(sel.T)] = True
        # The moved voxels' bounding box on the posed lattice, one voxel wider.
        world = sel @ rest.linear.T + rest.affine[:3, 3]
        moved = world @ m[:3, :3].T + m[:3, 3]
        pijk = (moved - posed.affine[:3, 3]) @ np.linalg.inv(posed.linear).T
        lo = np.maximum(np.floor(pijk.min(axis=0)).astype(int) - 1, 0)
        hi = np.minimum(np.ceil(pijk.max(axis=0)).astype(int) + 2, np.array(posed.data.shape))
        if np.any(hi <= lo):
            continue
        grid = np.stack(np.meshgrid(*[np.arange(a, b) for a, b in zip(lo, hi)], indexing="ij"), axis=-1).reshape(-1, 3)
        pw = grid @ posed.linear.T + posed.affine[:3, 3]
        minv = np.linalg.inv(m)
        back = pw @ minv[:3, :3].T + minv[:3, 3]
        rijk = np.rint(back @ inv_rest[:3, :3].T + inv_rest[:3, 3]).astype(np.int64)
        inside = np.all((rijk >= 0) & (rijk < shape), axis=1)
        hit = np.zeros(len(grid), bool)
        hit[inside] = member[tuple(rijk[inside].T)]
        out[tuple(grid[hit].T)] = True
    return out


def patella_rows(ijk, rest, superior):
    """Which voxels of a side's lower-leg bones (rows of ijk) are its patella: the 26-connected pieces but the
    largest whose centre lies above the largest's top (as voxmorph's articulated mesh finds it below its knee)."""
    mask = np.zeros(rest.data.shape, bool)
    mask[tuple(ijk.T)] = True
    pieces, n = ndimage.label(mask, structure=np.ones((3, 3, 3), bool))
    at = pieces[tuple(ijk.T)]
    if n < 2:
        return np.zeros(len(ijk), bool)
    height = (ijk @ rest.linear.T + rest.affine[:3, 3]) @ superior
    largest = np.argmax(np.bincount(at)[1:]) + 1
    top = height[at == largest].max()
    out = np.zeros(len(ijk), bool)
    for k in range(1, n + 1):
        sel = at == k
        if k != largest and height[sel].mean() > top:
            out |= sel
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0], formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("rest")
    ap.add_argument("posed")
    ap.add_argument("organs")
    ap.add_argument("parts", help="body-part grid of REST (voxmorph parts -o)")
    ap.add_argument("report", help="the deformation's JSON report (part_transforms)")
    ap.add_argument("--json", metavar="OUT", help="also write the rows as JSON")
    ap.add_argument("--min-dice", type=float, help="exit 1 when a bone's Dice is below this")
    ap.add_argument("--max-volume-pct", type=float, help="exit 1 when a bone's volume differs from its reference's by more (%%)")
    args = ap.parse_args()

    organs = read_organs(args.organs)
    bone_of_label = {l: b for l, n in organs.items() if (b := classify_bone(n))}
    rest, posed = Grid(args.rest, bone_of_label), Grid(args.posed, bone_of_label)
    parts = np.asarray(nib.load(args.parts).dataobj)
    if parts.shape != rest.data.shape:
        raise SystemExit(f"{args.parts}: its dims {parts.shape} are not the rest grid's {rest.data.shape}")
    with open(args.report) as f:
        transforms = json.load(f).get("part_transforms")
    if not transforms:
        raise SystemExit(f"{args.report}: no part_transforms (a joint pose's report has them)")
    by_name = {t["part"]: t["matrix"] for t in transforms if "part" in t}
    frame = body_frame(rest)
    spacing = np.sqrt((posed.linear ** 2).sum(axis=0))

    rows = []
    for bone in ORDER:
        split = sides(rest, bone, frame)
        refs = {}
        for side, ijk in split.items():
            if len(ijk):
                ijk = ijk.astype(np.int64)
                # A bone the deformation moved as its own segment ("right_scapula"
                # in part_transforms, deform --articulated) follows that transform.
                own = by_name.get(f"{side}_{bone}")
                patella = by_name.get(f"{side}_patella") if bone == "lower_leg_bones" else None
                if patella is not None:
                    # The patella moved as its own segment ("right_patella"), the rest by their parts.
                    on = patella_rows(ijk, rest, frame["superior"])
                    ref = reference(rest, posed, ijk[~on], parts[tuple(ijk[~on].T)], transforms)
                    if on.any():
                        ref |= reference(rest, posed, ijk[on], parts[tuple(ijk[on].T)], transforms, patella)
                    refs[side] = (len(ijk), ref)
                else:
                    refs[side] = (len(ijk), reference(rest, posed, ijk, parts[tuple(ijk.T)], transforms, own))
        if not refs:
            continue
        posed_bone = posed.mask(bone)
        if len(refs) == 1:
            owner = {next(iter(refs)): posed_bone}
        else:
            dist = {s: ndimage.distance_transform_edt(~r, sampling=spacing) for s, (_, r) in refs.items()}
            right_nearer = dist["right"] <= dist["left"]
            owner = {"right": posed_bone & right_nearer, "left": posed_bone & ~right_nearer}
        for side, (rest_voxels, ref) in refs.items():
            p = owner[side]
            both = np.count_nonzero(p & ref)
            np_, nr = np.count_nonzero(p), np.count_nonzero(ref)
            rows.append({"bone": bone, "side": side, "rest_voxels": rest_voxels, "reference_voxels": nr, "posed_voxels": np_,
                         "dice": 2.0 * both / (np_ + nr) if np_ + nr else 1.0,
                         "volume_pct": 100.0 * (np_ - nr) / nr if nr else float("nan")})

    print(f"rest {args.rest}, posed {args.posed}: each bone against its rest bone moved by its part's transform")
    print(f"{'bone':<18} {'side':<6} {'rest vox':>9} {'reference':>10} {'posed':>9} {'Dice':>7} {'vol %':>7}")
    failed = []
    for r in rows:
        bad = r["rest_voxels"] >= 1000 and ((args.min_dice is not None and r["dice"] < args.min_dice) or
                                            (args.max_volume_pct is not None and abs(r["volume_pct"]) > args.max_volume_pct))
        if bad:
            failed.append(f"{r['bone']} {r['side']}")
        print(f"{r['bone']:<18} {r['side']:<6} {r['rest_voxels']:>9} {r['reference_voxels']:>10} {r['posed_voxels']:>9}"
              f" {r['dice']:>7.4f} {r['volume_pct']:>+7.2f}" + ("  *" if bad else ""))
    big = [r for r in rows if r["rest_voxels"] >= 1000]
    if big:
        print(f"bones of 1000 voxels or more: {len(big)}, lowest Dice {min(r['dice'] for r in big):.4f}, "
              f"largest |volume change| {max(abs(r['volume_pct']) for r in big):.2f} %")
    if args.json:
        with open(args.json, "w") as f:
            json.dump({"rest": args.rest, "posed": args.posed, "report": args.report, "bones": rows}, f, indent=1)
    if failed:
        print("outside the bounds: " + ", ".join(failed))
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
