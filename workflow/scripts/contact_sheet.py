#!/usr/bin/env python3
"""The contact sheet of a posture study: every row's front and side views of
the posed grid side by side, named by phantom and pose, in study order.

contact_sheet.py STUDY.tsv OUT.png [columns]
"""

import json
import os
import sys

from PIL import Image, ImageDraw, ImageFont

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from study import read_study  # noqa: E402

BACKGROUND = (22, 24, 32)
TEXT = (235, 235, 235)
DIM = (160, 165, 180)
FONT_FILES = ["/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf", "DejaVuSans.ttf"]


def font(size):
    for f in FONT_FILES:
        try:
            return ImageFont.truetype(f, size)
        except OSError:
            pass
    return ImageFont.load_default()


def caption(row):
    pose = os.path.splitext(os.path.basename(row.pose))[0]
    try:
        with open(row.pose) as f:
            name = json.load(f).get("name", "")
    except (OSError, ValueError):
        name = ""
    return f"{row.phantom}: {pose}", name


def fit(draw, text, face, width):
    """The text shortened with an ellipsis to fit `width` pixels."""
    if draw.textlength(text, font=face) <= width:
        return text
    while text and draw.textlength(text + "...", font=face) > width:
        text = text[:-1]
    return text + "..."


def main(study, out, columns=4):
    rows = read_study(study, check_files=False)
    tiles = []
    for row in rows:
        views = [Image.open(os.path.join(row.output, f"{v}.png")).convert("RGB") for v in ("front", "side")]
        tiles.append((row, views))
    view_w = max(v.width for _, vs in tiles for v in vs)
    view_h = max(v.height for _, vs in tiles for v in vs)
    title, subtitle = font(max(12, view_w // 14)), font(max(10, view_w // 20))
    pad = 8
    caption_h = title.size + subtitle.size + 3 * pad if hasattr(title, "size") else 40
    tile_w, tile_h = 2 * view_w + pad, view_h + caption_h
    columns = max(1, min(int(columns), len(tiles)))
    lines = (len(tiles) + columns - 1) // columns
    sheet = Image.new("RGB", (columns * tile_w + (columns + 1) * pad, lines * tile_h + (lines + 1) * pad), BACKGROUND)
    draw = ImageDraw.Draw(sheet)
    for n, (row, views) in enumerate(tiles):
        x = pad + (n % columns) * (tile_w + pad)
        y = pad + (n // columns) * (tile_h + pad)
        for k, v in enumerate(views):
            sheet.paste(v, (x + k * (view_w + pad), y))
        first, second = caption(row)
        draw.text((x + 4, y + view_h + pad), fit(draw, first, title, tile_w - 8), fill=TEXT, font=title)
        if second:
            draw.text((x + 4, y + view_h + 2 * pad + getattr(title, "size", 12)), fit(draw, second, subtitle, tile_w - 8),
                      fill=DIM, font=subtitle)
    temp = out + ".partial.png"
    sheet.save(temp)
    os.replace(temp, out)


if __name__ == "__main__":
    if len(sys.argv) not in (3, 4):
        sys.exit("usage: contact_sheet.py STUDY.tsv OUT.png [columns]")
    main(*sys.argv[1:])
