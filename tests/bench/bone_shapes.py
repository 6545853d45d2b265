#!/usr/bin/python3
"""Bone volumes and principal lengths of a label grid at rest and posed.

    tests/bench/bone_shapes.py REST POSED ORGANS [--json OUT.json] [--labels] [--voxel-extent]

REST and POSED are label grids that NIfTI reads (`voxmorph deform` writes the
posed grid), ORGANS the organ table (ID name tissue density) of both. The
bones are the organ labels that geometry/skeleton/bones.cpp classifies as
bones: only the words before the first comma of the organ name count
("Humeri, upper half, cortical" -> humerus; "Kidney, left, pelvis" is no
bone), and every label of a bone (cortical, spongiosa, medullary cavity) is
counted together. Paired bones (clavicles, scapulae, humeri, ulnae and radii,
hand bones, femora, tibiae fibulae and patellae, foot bones) are split into
right and left: each 26-connected component of the bone goes to the side of
the mid-sagittal plane its centroid lies on. The plane passes through the
centroid of the thoracic and lumbar spine, sacrum and sternum voxels; the
body's axes come from the bones as in voxmorph parts (superior: pelvis ->
cranium, anterior: spine -> sternum, right = anterior x superior, each
snapped to the nearest axis of the world frame).

Per bone and side: the volume (voxel count times voxel volume) at rest and
posed, and the three principal lengths: the square roots of the eigenvalues of
the covariance of the voxels' centre coordinates in mm (world frame of the
NIfTI affine), largest first (--voxel-extent adds the covariance of a uniform
voxel, spacing^2 / 12 per axis). A rigid motion keeps all of them; a change
is deformation of the bone or its resampling on the grid (on the ICRP 110 AM,
2.137 x 2.137 x 8 mm voxels, the right femur turned rigidly by 90 degrees and
resampled nearest-neighbour changes by +1.5 % in volume and +0.1, +0.2, +1.6 %
in L1, L2, L3; the right humerus by -1.2 % and -1.2, +0.7, +0.8 %).

Needs numpy and nibabel (Debian: python3-numpy python3-nibabel); the
connected components use scipy.ndimage when it is installed, otherwise each
voxel goes to its own side of the plane (the output says which).
"""

import argparse
import json
import re
import sys

import nibabel as nib
import numpy as np

try:
    from scipy import ndimage
except ImportError:  # per-voxel side of the mid-sagittal plane instead
    ndimage = None

# geometry/skeleton/bones.cpp: kBoneNames and isPaired.
PAIRED = {"clavicle", "scapula", "humerus", "forearm_bones", "hand_bones", "femur", "lower_leg_bones", "foot_bones"}
ORDER = ["cranium", "mandible", "cervical_spine", "thoracic_spine", "lumbar_spine", "sacrum", "pelvis", "ribs", "sternum",
         "clavicle", "scapula", "humerus", "forearm_bones", "hand_bones", "femur", "lower_leg_bones", "foot_bones"]


def words(name):
    """geometry/organ_table.cpp organNameWords: runs of letters, lower case."""
    return re.findall(r"[a-z]+", name.lower())


def starts(ws, prefixes):
    return any(w.startswith(p) for w in ws for p in prefixes)


def classify_bone(organ_name):
    """geometry/skeleton/bones.cpp classifyBone, same order of tests."""
    w = words(organ_name.split(",", 1)[0])
    if not w or starts(w, ["cartilage", "marrow", "muscle", "skin", "blood", "lymph"]):
        return None
    if "spine" in w or starts(w, ["vertebra"]):
        if "cervical" in w:
            return "cervical_spine"
        if "thoracic" in w:
            return "thoracic_spine"
        if "lumbar" in w:
            return "lumbar_spine"
        return None
    if starts(w, ["humer"]):
        return "humerus"
    if starts(w, ["ulna", "radius", "radii"]):
        return "forearm_bones"
    if starts(w, ["wrist", "carp", "metacarp"]) or (starts(w, ["hand"]) and starts(w, ["bone"])):
        return "hand_bones"
    if starts(w, ["clavic"]):
        return "clavicle"
    if starts(w, ["scapul"]):
        return "scapula"
    if starts(w, ["femor", "femur"]):
        return "femur"
    if starts(w, ["tibia", "fibula", "patell"]):
        return "lower_leg_bones"
    if starts(w, ["ankle", "tars", "metatars", "calcane", "talus"]) or (("foot" in w or "feet" in w) and starts(w, ["bone"])):
        return "foot_bones"
    if starts(w, ["crani", "skull"]):
        return "cranium"
    if starts(w, ["mandib"]):
        return "mandible"
    if starts(w, ["sacrum", "coccyx"]):
        return "sacrum"
    if starts(w, ["pelvis", "coxa", "ilium", "ischium", "pubis"]):
        return "pelvis"
    if starts(w, ["rib"]):
        return "ribs"
    if starts(w, ["stern"]):
        return "sternum"
    return None


def display_name(label_names, bone):
    """The organ names' common part up to a comma: 'Humeri, upper half, cortical' ... -> 'Humeri'."""
    prefix = label_names[0]
    for n in label_names[1:]:
        while not n.startswith(prefix):
            prefix = prefix[:-1]
    if len(label_names) > 1 or "," in prefix:
        prefix = prefix[:prefix.rfind(",")] if "," in prefix else ""
    return prefix.strip() or bone


def read_organs(path):
    """geometry/organ_table.cpp OrganTable::read: lines 'ID name... tissue density' whose first token is digits."""
    organs = {}
    with open(path, encoding="latin-1") as f:
        for line in f:
            tok = line.split()
            if len(tok) < 4 or not tok[0].isdigit():
                continue
            organs[int(tok[0])] = " ".join(tok[1:-2])
    return organs


class Grid:
    def __init__(self, path, bone_of_label):
        img = nib.load(path)
        self.path = path
        self.data = np.asarray(img.dataobj)
        if not np.issubdtype(self.data.dtype, np.integer):
            self.data = np.rint(self.data).astype(np.int64)
        self.affine = img.affine
        self.linear = img.affine[:3, :3]
        self.voxel_mm3 = abs(np.linalg.det(self.linear))
        # Covariance of a uniform voxel: its edge vectors, each uniform on [-1/2, 1/2].
        self.voxel_cov = self.linear @ self.linear.T / 12.0
        n = int(max(self.data.max(), max(bone_of_label) if bone_of_label else 0)) + 1
        self.lut = np.full(n, -1, np.int16)
        for label, bone in bone_of_label.items():
            if label < n:
                self.lut[label] = ORDER.index(bone)
        self.bone_index = self.lut[self.data]

    def world(self, ijk):
        return ijk @ self.linear.T + self.affine[:3, 3]

    def mask(self, bone):
        return self.bone_index == ORDER.index(bone)

    def points(self, bones):
        m = np.isin(self.bone_index, [ORDER.index(b) for b in bones])
        return self.world(np.argwhere(m).astype(np.float64))


def snap(v):
    """The nearest grid-independent axis (+-x, +-y, +-z) of a world direction."""
    out = np.zeros(3)
    k = int(np.argmax(np.abs(v)))
    out[k] = np.sign(v[k])
    return out


def body_frame(grid):
    """Superior, anterior, right and a mid-sagittal point from the axial bones, as voxmorph parts finds them."""
    def centroid(bones):
        p = grid.points(bones)
        if len(p) == 0:
            raise SystemExit(f"{grid.path}: no voxels of {', '.join(bones)}: the body's axes cannot be found")
        return p.mean(axis=0)
    spine = centroid(["thoracic_spine", "lumbar_spine"])
    superior = snap(centroid(["cranium"]) - centroid(["pelvis", "sacrum"]))
    a = centroid(["sternum"]) - spine
    a -= a.dot(superior) * superior
    anterior = snap(a)
    right = np.cross(anterior, superior)
    mid = centroid(["thoracic_spine", "lumbar_spine", "sacrum", "sternum"])
    return {"superior": superior, "anterior": anterior, "right": right, "midline_point": mid}


def shape(points, voxel_cov, voxel_mm3, extent):
    n = len(points)
    if n < 2:
        return {"voxels": n, "volume_ml": n * voxel_mm3 * 1e-3, "lengths_mm": [float("nan")] * 3}
    c = np.cov(points, rowvar=False, bias=True)
    if extent:
        c = c + voxel_cov
    ev = np.sort(np.clip(np.linalg.eigvalsh(c), 0.0, None))[::-1]
    return {"voxels": int(n), "volume_ml": n * voxel_mm3 * 1e-3, "lengths_mm": [float(x) for x in np.sqrt(ev)]}


def sides(grid, bone, frame):
    """{'right': ijk, 'left': ijk} for a paired bone, {'axial': ijk} otherwise."""
    m = grid.mask(bone)
    ijk = np.argwhere(m).astype(np.float64)
    if bone not in PAIRED:
        return {"axial": ijk}
    right, mid = frame["right"], frame["midline_point"]
    if ndimage is not None and len(ijk):
        comp, count = ndimage.label(m, structure=np.ones((3, 3, 3), bool))
        ids = comp[m]
        sums = np.zeros((count + 1, 3))
        np.add.at(sums, ids, grid.world(ijk))
        sizes = np.bincount(ids, minlength=count + 1)
        centroids = sums[1:] / np.maximum(sizes[1:, None], 1)
        comp_right = np.concatenate([[False], (centroids - mid) @ right > 0.0])
        on_right = comp_right[ids]
    else:
        on_right = (grid.world(ijk) - mid) @ right > 0.0
    return {"right": ijk[on_right], "left": ijk[~on_right]}


def pct(after, before):
    return 100.0 * (after - before) / before if before else float("nan")


def measure(rest, posed, names, extent, per_label, bone_of_label):
    fr, fp = body_frame(rest), body_frame(posed)
    rows = []
    for bone in ORDER:
        labels = sorted(l for l, b in bone_of_label.items() if b == bone)
        if not labels:
            continue
        sr, sp = sides(rest, bone, fr), sides(posed, bone, fp)
        for side in sr:
            a = shape(rest.world(sr[side]), rest.voxel_cov, rest.voxel_mm3, extent)
            b = shape(posed.world(sp.get(side, np.zeros((0, 3)))), posed.voxel_cov, posed.voxel_mm3, extent)
            if a["voxels"] == 0 and b["voxels"] == 0:
                continue
            row = {"bone": bone, "name": names[bone], "side": side, "labels": labels,
                   "rest": a, "posed": b, "volume_change_pct": pct(b["volume_ml"], a["volume_ml"]),
                   "length_change_pct": [pct(y, x) for x, y in zip(a["lengths_mm"], b["lengths_mm"])]}
            if per_label:
                row["per_label"] = []
                lr = rest.data[tuple(sr[side].astype(np.int64).T)]
                lp = posed.data[tuple(sp.get(side, np.zeros((0, 3))).astype(np.int64).T)]
                for l in labels:
                    vr = int(np.count_nonzero(lr == l))
                    vp = int(np.count_nonzero(lp == l))
                    row["per_label"].append({"label": l, "voxels_rest": vr, "voxels_posed": vp,
                                             "volume_change_pct": pct(vp * posed.voxel_mm3, vr * rest.voxel_mm3)})
            rows.append(row)
    return rows, fr


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0], formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("rest", help="label grid at rest (.nii / .nii.gz)")
    ap.add_argument("posed", help="posed label grid (voxmorph deform -o)")
    ap.add_argument("organs", help="organ table (ID name tissue density)")
    ap.add_argument("--json", metavar="OUT", help="also write the rows as JSON ('-' for stdout, then no table)")
    ap.add_argument("--labels", action="store_true", help="also list the voxel counts of each bone label (per side)")
    ap.add_argument("--voxel-extent", action="store_true", help="add a uniform voxel's covariance (spacing^2 / 12 per axis) to each bone's")
    args = ap.parse_args()

    organs = read_organs(args.organs)
    bone_of_label = {l: b for l, n in organs.items() if (b := classify_bone(n))}
    if not bone_of_label:
        raise SystemExit(f"{args.organs}: the organ table names no bones")
    names = {}
    for bone in set(bone_of_label.values()):
        names[bone] = display_name([organs[l] for l in bone_of_label if bone_of_label[l] == bone], bone)
    rest, posed = Grid(args.rest, bone_of_label), Grid(args.posed, bone_of_label)
    rows, frame = measure(rest, posed, names, args.voxel_extent, args.labels, bone_of_label)

    if args.json:
        out = {"rest": args.rest, "posed": args.posed, "organs": args.organs,
               "voxel_extent": args.voxel_extent,
               "sides": "26-connected components, centroid side of the mid-sagittal plane" if ndimage is not None
                        else "each voxel's side of the mid-sagittal plane",
               "frame": {k: [float(x) for x in v] for k, v in frame.items()}, "bones": rows}
        text = json.dumps(out, indent=1)
        if args.json == "-":
            print(text)
            return
        with open(args.json, "w") as f:
            f.write(text + "\n")

    print(f"rest {args.rest}, posed {args.posed}")
    print("sides: " + ("26-connected components by centroid" if ndimage is not None else "each voxel by its own position")
          + " against the mid-sagittal plane; lengths: sqrt of the covariance eigenvalues, mm"
          + (", voxel extent included" if args.voxel_extent else ""))
    head = f"{'bone':<30} {'side':<6} {'vol rest ml':>11} {'posed':>9} {'%':>7}"
    for k in (1, 2, 3):
        head += f" {'L' + str(k) + ' rest':>8} {'posed':>7} {'%':>6}"
    print(head)
    print("-" * len(head))
    for r in rows:
        line = (f"{r['name']:<30} {r['side']:<6} {r['rest']['volume_ml']:>11.1f} {r['posed']['volume_ml']:>9.1f}"
                f" {r['volume_change_pct']:>+7.2f}")
        for x, y, d in zip(r["rest"]["lengths_mm"], r["posed"]["lengths_mm"], r["length_change_pct"]):
            line += f" {x:>8.1f} {y:>7.1f} {d:>+6.1f}"
        print(line)
        for pl in r.get("per_label", []):
            print(f"    {pl['label']:>4} {organs[pl['label']]:<44} {pl['voxels_rest']:>8} -> {pl['voxels_posed']:>8}"
                  f" {pl['volume_change_pct']:>+7.2f} %")


if __name__ == "__main__":
    sys.exit(main())
