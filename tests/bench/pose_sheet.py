#!/usr/bin/python3
"""A contact sheet of a posed grid: whole-body views and close-ups of posed joints.

    tests/bench/pose_sheet.py POSED ORGANS PARTS_REPORT DEFORM_REPORT OUT.png VIEW [VIEW ...]
        [--voxmorph build/release/voxmorph] [--scale 0.8]

POSED is the grid `voxmorph deform` wrote, DEFORM_REPORT its --report (the parts'
transforms), PARTS_REPORT the --report of `voxmorph parts` on the rest grid (the joints'
rest centres). A VIEW is "front", "back", "side" (the body's right) or "left" for the
whole body, or JOINT:DIR for a close-up 380 mm from the joint's posed centre, DIR one of
front, back, side, left, below (the joint moved by its child part's transform). Each view
is rendered by `voxmorph render --cpu` (smooth shading, colours by organ) and labelled;
the sheet is scaled by --scale and written with a 256-colour palette.

Needs numpy and PIL (Debian: python3-numpy python3-pil).
"""

import argparse
import json
import os
import subprocess
import tempfile

import numpy as np
from PIL import Image, ImageDraw

DIRECTIONS = {"front": (0, -1, 0), "back": (0, 1, 0), "side": (-1, 0, 0), "left": (1, 0, 0), "below": (0, -0.3, -1)}
WHOLE = {"front": "azimuth=0,elevation=5", "back": "azimuth=180,elevation=5", "side": "azimuth=-90,elevation=5",
         "left": "azimuth=90,elevation=5"}


def posed_joints(parts_report, deform_report):
    transforms = {t["part"]: np.array(t["matrix"]) for t in deform_report["part_transforms"]}
    return {j["name"]: (transforms[j["child"]] @ np.array(j["center_mm"] + [1.0]))[:3] for j in parts_report["joints"]}


def camera(view, joints):
    if ":" not in view:
        if view not in WHOLE:
            raise SystemExit(f"unknown view '{view}' (front, back, side, left, or JOINT:DIR)")
        return WHOLE[view], "300x400"
    name, direction = view.split(":", 1)
    if name not in joints or direction not in DIRECTIONS:
        raise SystemExit(f"unknown view '{view}': joints {', '.join(joints)}; directions {', '.join(DIRECTIONS)}")
    target = joints[name]
    d = np.array(DIRECTIONS[direction], float)
    eye = target + 380.0 * d / np.linalg.norm(d)
    up = "0,1,0" if direction == "below" else "0,0,1"
    return (f"eye={eye[0]:.0f},{eye[1]:.0f},{eye[2]:.0f},target={target[0]:.0f},{target[1]:.0f},{target[2]:.0f},"
            f"up={up},fov=40"), "400x400"


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0], formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("posed")
    ap.add_argument("organs")
    ap.add_argument("parts_report")
    ap.add_argument("deform_report")
    ap.add_argument("out")
    ap.add_argument("views", nargs="+")
    ap.add_argument("--voxmorph", default="build/release/voxmorph")
    ap.add_argument("--scale", type=float, default=0.8)
    args = ap.parse_args()
    with open(args.parts_report) as f:
        parts = json.load(f)
    with open(args.deform_report) as f:
        deform = json.load(f)
    joints = posed_joints(parts, deform)
    tiles = []
    with tempfile.TemporaryDirectory() as tmp:
        for i, view in enumerate(args.views):
            cam, size = camera(view, joints)
            png = os.path.join(tmp, f"{i}.png")
            subprocess.run([args.voxmorph, "render", args.posed, "--organs", args.organs, "--size", size, "--camera", cam, "--cpu",
                            "-q", "-o", png], check=True)
            tile = Image.open(png).convert("RGB")
            ImageDraw.Draw(tile).text((6, 4), view, fill=(255, 255, 255))
            tiles.append(tile)
    sheet = Image.new("RGB", (sum(t.width for t in tiles), max(t.height for t in tiles)), (20, 20, 28))
    x = 0
    for tile in tiles:
        sheet.paste(tile, (x, 0))
        x += tile.width
    if args.scale != 1.0:
        sheet = sheet.resize((round(sheet.width * args.scale), round(sheet.height * args.scale)), Image.LANCZOS)
    sheet.quantize(256).save(args.out, optimize=True)


if __name__ == "__main__":
    main()
