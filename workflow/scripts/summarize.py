#!/usr/bin/env python3
"""The summary of a posture study, from each row's report.json and grids.

summary.py STUDY.tsv SUMMARY.csv ORGANS.csv

SUMMARY.csv is wide: one row per study row (phantom x pose), the columns of
COLUMNS, then one column per organ "mass_g:<label>:<organ>" with the organ's
mass in the posed grid (with an organ table; "voxels:<label>" with its voxel
count without one), empty where a phantom lacks the label.
ORGANS.csv is long: one row per study row and organ (LONG_COLUMNS).
The organs' voxels and masses are measured on the source and posed grids
through the voxmorph Python module (on PYTHONPATH: build/<preset>/python,
which the Snakefile sets); the whole-body, mesh, distortion and provenance
columns come from the report.
Both are written to a temporary file and renamed into place.
"""

import csv
import json
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from study import read_study  # noqa: E402
import voxmorph  # noqa: E402

# (column, description); the description goes to docs/STUDIES.md.
COLUMNS = [
    ("phantom", "the study row's phantom"),
    ("pose", "pose file name without .json"),
    ("pose_name", "the pose's \"name\""),
    ("output", "the row's output folder"),
    ("options", "the row's deform options"),
    ("voxels_before", "foreground voxels of the source"),
    ("voxels_after", "foreground voxels of the posed grid"),
    ("volume_change_pct", "whole-body volume change, %"),
    ("mass_before_g", "whole-body mass of the source, g (with an organ table)"),
    ("mass_after_g", "whole-body mass of the posed grid, g"),
    ("mass_change_pct", "whole-body mass change, %"),
    ("largest_organ_change_pct", "largest volume (= mass) change of an organ of 1000 voxels or more, %"),
    ("largest_organ_change", "that organ"),
    ("tm_vertices", "transfer mesh vertices"),
    ("tm_tets", "transfer mesh tets"),
    ("tm_inverted_tets", "transfer mesh tets inverted by the deformation"),
    ("tm_inverted_volume_fraction", "their share of the rest volume"),
    ("tm_vertices_outside_cage", "transfer mesh vertices placed by the propagation"),
    ("refinement_max_error", "deformation-adaptive refinement: largest error after the last iteration"),
    ("refinement_mean_error", "mean error after the last iteration"),
    ("angle_mean_deg", "dual-edge angle distortion: mean, degrees (90 undistorted)"),
    ("angle_rms_deviation_deg", "rms deviation from 90 degrees"),
    ("stretch_mean", "edge stretch: mean (1 undistorted)"),
    ("stretch_rms_deviation", "rms deviation from 1"),
    ("front_area_mm2_rest", "projected area seen from the front (along y, anterior-posterior) at rest, mm^2"),
    ("front_area_mm2", "the same, posed"),
    ("front_area_change_pct", "its change, %"),
    ("side_area_mm2_rest", "projected area seen from the side (along x) at rest, mm^2"),
    ("side_area_mm2", "the same, posed"),
    ("side_area_change_pct", "its change, %"),
    ("top_area_mm2_rest", "projected area seen from the top (along z) at rest, mm^2"),
    ("top_area_mm2", "the same, posed"),
    ("top_area_change_pct", "its change, %"),
    ("height_mm_rest", "extent along z at rest, mm"),
    ("height_mm", "the same, posed"),
    ("deform_seconds", "wall time of voxmorph deform, s"),
    ("engine", "rasterization engine"),
    ("voxmorph_version", "provenance: voxmorph version"),
    ("git_describe", "provenance: git describe of the build"),
    ("grid_sha256", "provenance: SHA-256 of the grid file"),
    ("organs_sha256", "provenance: SHA-256 of the organ table"),
    ("pose_sha256", "provenance: SHA-256 of the pose file"),
    ("command_line", "provenance: the deform command line"),
]

LONG_COLUMNS = ["phantom", "pose", "label", "organ", "voxels_before", "voxels_after", "volume_change_pct", "mass_before_g",
                "mass_after_g", "mass_change_pct"]


def change(before, after):
    return 100.0 * (after - before) / before if before else ""


def pose_name(path):
    try:
        with open(path) as f:
            return json.load(f).get("name", "")
    except (OSError, ValueError):
        return ""


def organ_figures(grid, organs):
    """Per label > 0 of a grid file: (name, voxels, mass in g), the name "" and the mass 0
    for a label the organ table lacks, the mass None without a table."""
    stats = voxmorph.Grid.read(grid).statistics(organs or None)
    names = stats.get("name", [None] * len(stats["label"]))
    masses = stats.get("mass_g", [None] * len(stats["label"]))
    return {label: (name or "", voxels, (mass or 0.0) if organs else None)
            for label, name, voxels, mass in zip(stats["label"], names, stats["voxels"], masses) if label > 0}


def summarize(row, report, rest_organs, posed_organs):
    whole = report["whole_body"]
    tm = report["transfer_mesh"]
    steps = report["refinement"]["iterations"]
    largest = report.get("largest_change_above_threshold") or {}
    projection = report["body_projection"]
    rest, posed = projection["rest"], projection["posed"]
    digests = {d["role"]: d["sha256"] for d in report["provenance"]["inputs"]}
    out = {
        "phantom": row.phantom,
        "pose": os.path.splitext(os.path.basename(row.pose))[0],
        "pose_name": pose_name(row.pose),
        "output": row.output,
        "options": " ".join(row.options),
        "voxels_before": whole["voxels_before"],
        "voxels_after": whole["voxels_after"],
        "volume_change_pct": whole["volume_change_pct"],
        "mass_before_g": whole.get("mass_before_g", ""),
        "mass_after_g": whole.get("mass_after_g", ""),
        "mass_change_pct": whole.get("mass_change_pct", ""),
        "largest_organ_change_pct": largest.get("change_pct", ""),
        "largest_organ_change": largest.get("name", ""),
        "tm_vertices": tm["vertices"],
        "tm_tets": tm["tets"],
        "tm_inverted_tets": tm["tets_inverted_by_deformation"],
        "tm_inverted_volume_fraction": tm["inverted_rest_volume_fraction"],
        "tm_vertices_outside_cage": tm["vertices_outside_cage"],
        "refinement_max_error": steps[-1]["max_error"] if steps else "",
        "refinement_mean_error": steps[-1]["mean_error"] if steps else "",
        "angle_mean_deg": report["distortion"]["angle_deg"]["mean"],
        "angle_rms_deviation_deg": report["distortion"]["angle_deg"]["rms_deviation"],
        "stretch_mean": report["distortion"]["stretch"]["mean"],
        "stretch_rms_deviation": report["distortion"]["stretch"]["rms_deviation"],
        "height_mm_rest": rest["height_mm"],
        "height_mm": posed["height_mm"],
        "deform_seconds": report["total_seconds"],
        "engine": report["engine"],
        "voxmorph_version": report["provenance"]["voxmorph_version"],
        "git_describe": report["provenance"]["git_describe"] or "",
        "grid_sha256": digests.get("grid", ""),
        "organs_sha256": digests.get("organs", ""),
        "pose_sha256": digests.get("pose", ""),
        "command_line": report["provenance"]["command_line"],
    }
    for view in ("front", "side", "top"):
        before, after = rest[f"{view}_area_mm2"], posed[f"{view}_area_mm2"]
        out[f"{view}_area_mm2_rest"] = before
        out[f"{view}_area_mm2"] = after
        out[f"{view}_area_change_pct"] = change(before, after)
    organs, long_rows = {}, []
    nobody = ("", 0, 0.0 if row.organs else None)
    for label in sorted(rest_organs.keys() | posed_organs.keys()):
        name, voxels_before, mass_before = rest_organs.get(label, nobody)
        name, voxels_after, mass_after = posed_organs.get(label, (name, 0, nobody[2]))
        masses = mass_before is not None
        key = f"mass_g:{label}:{name}" if masses else f"voxels:{label}"
        organs[key] = mass_after if masses else voxels_after
        long_rows.append({
            "phantom": out["phantom"], "pose": out["pose"], "label": label, "organ": name,
            "voxels_before": voxels_before, "voxels_after": voxels_after,
            "volume_change_pct": change(voxels_before, voxels_after) or 0.0,
            "mass_before_g": mass_before if masses else "", "mass_after_g": mass_after if masses else "",
            "mass_change_pct": (change(voxels_before, voxels_after) or 0.0) if masses else "",
        })
    return out, organs, long_rows


def write_csv(path, header, rows):
    temp = f"{path}.partial"
    with open(temp, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=header, restval="")
        w.writeheader()
        w.writerows(rows)
    os.replace(temp, path)


def organ_key(key):
    kind, label = key.split(":")[:2]
    return (kind, int(label))


def main(study, wide_path, long_path):
    rows = read_study(study, check_files=False)
    wide, organ_columns, long_rows, sources = [], {}, [], {}
    for row in rows:
        with open(os.path.join(row.output, "report.json")) as f:
            report = json.load(f)
        source = (row.grid, row.organs)
        if source not in sources:
            sources[source] = organ_figures(row.grid, row.organs)
        after = organ_figures(os.path.join(row.output, "posed.nii.gz"), row.organs)
        out, organs, organ_rows = summarize(row, report, sources[source], after)
        organ_columns.update(dict.fromkeys(organs))
        wide.append({**out, **organs})
        long_rows += organ_rows
    header = [c for c, _ in COLUMNS] + sorted(organ_columns, key=organ_key)
    write_csv(wide_path, header, wide)
    write_csv(long_path, LONG_COLUMNS, long_rows)


if __name__ == "__main__":
    if len(sys.argv) != 4:
        sys.exit("usage: summarize.py STUDY.tsv SUMMARY.csv ORGANS.csv")
    main(*sys.argv[1:])
