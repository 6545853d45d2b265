#!/usr/bin/env python3
"""Dark-line fraction of a rendered image: the share of the body's pixels (those
that differ from the background colour) whose luminance is under a fraction
(default 60 %) of the median luminance of their 5x5 neighbourhood (every pixel
of the window, background included, edge pixels replicated).

Thin dark lines across a lit surface (voxel faces seen edge-on under the
headlight) are such pixels; a smoothly shaded surface has almost none.

Usage: dark_lines.py IMAGE.png [--background R,G,B] [--ratio 0.6] [--max F]
Prints the fraction; with --max, exits 1 when the fraction is not under F.
"""

import argparse
import sys

import numpy as np
from PIL import Image


def dark_line_fraction(rgb, background=(22, 24, 29), ratio=0.6, window=5):
    """rgb: H x W x 3 uint8. Returns (dark pixels, body pixels)."""
    rgb = np.asarray(rgb)
    body = np.any(rgb != np.array(background, dtype=rgb.dtype), axis=2)
    luma = rgb.astype(np.float64) @ np.array([0.299, 0.587, 0.114])
    r = window // 2
    padded = np.pad(luma, r, mode='edge')
    h, w = luma.shape
    stack = np.stack([padded[dy:dy + h, dx:dx + w] for dy in range(window) for dx in range(window)])
    median = np.median(stack, axis=0)
    dark = body & (luma < ratio * median)
    return int(dark.sum()), int(body.sum())


def main():
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('image')
    parser.add_argument('--background', default='22,24,29', help='background colour R,G,B (RaycastShading)')
    parser.add_argument('--ratio', type=float, default=0.6)
    parser.add_argument('--max', type=float, default=None, help='fail unless the fraction is under this')
    args = parser.parse_args()
    background = tuple(int(v) for v in args.background.split(','))
    rgb = np.asarray(Image.open(args.image).convert('RGB'))
    dark, body = dark_line_fraction(rgb, background, args.ratio)
    if body == 0:
        print(f'{args.image}: no body pixels', file=sys.stderr)
        return 1
    fraction = dark / body
    print(f'{args.image}: {dark} of {body} body pixels under {args.ratio:.0%} of their 5x5 median: {100 * fraction:.3f} %')
    if args.max is not None and not fraction < args.max:
        print(f'{args.image}: dark-line fraction {fraction:.5f} is not under {args.max}', file=sys.stderr)
        return 1
    return 0


if __name__ == '__main__':
    sys.exit(main())
