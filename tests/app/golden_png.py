#!/usr/bin/env python3
"""Compares screenshots with golden PNGs within the ray caster's tolerance.

  golden_png.py GOLDEN_DIR SHOT=GOLDEN [SHOT=GOLDEN ...]

Each screenshot must have its golden image's size, and at most 0.1 % of its
pixels may differ from it by more than 5/255 in a channel (the tolerance of
the viewer's golden images: float ties in the ray caster differ between
builds). Prints one line per pair; exit 1 on the first that fails. `load`
reads an 8-bit RGB PNG (what voxmorph writes) without third-party modules.
"""
import struct
import sys
import zlib

TOLERANCE = 5           # per channel, out of 255
DIFFERING_FRACTION = 0.001


def load(path):
    """(width, height, rows): rows of bytearrays, 3 bytes a pixel."""
    d = open(path, 'rb').read()
    w, h, depth, ctype = struct.unpack('>IIBB', d[16:26])
    if depth != 8 or ctype != 2:
        raise ValueError(f'{path}: not an 8-bit RGB PNG')
    i, idat = 8, b''
    while i < len(d):
        n = struct.unpack('>I', d[i:i + 4])[0]
        if d[i + 4:i + 8] == b'IDAT':
            idat += d[i + 8:i + 8 + n]
        i += 12 + n
    raw, rows, prev, stride = zlib.decompress(idat), [], bytearray(w * 3), w * 3
    for y in range(h):
        f, line = raw[y * (stride + 1)], bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for x in range(stride):
            a = line[x - 3] if x >= 3 else 0
            b = prev[x]
            c = prev[x - 3] if x >= 3 else 0
            if f == 1:
                line[x] = (line[x] + a) & 255
            elif f == 2:
                line[x] = (line[x] + b) & 255
            elif f == 3:
                line[x] = (line[x] + (a + b) // 2) & 255
            elif f == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                line[x] = (line[x] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        rows.append(line)
        prev = line
    return w, h, rows


def differing(a, b, w, h, x0=0):
    """Pixels of columns x0.. of a (w x h) that differ from b's by more than TOLERANCE."""
    return sum(1 for y in range(h) for x in range(x0, w)
               if max(abs(a[y][3 * x + k] - b[y][3 * x + k]) for k in range(3)) > TOLERANCE)


def main(argv):
    if len(argv) < 3 or any('=' not in p for p in argv[2:]):
        sys.exit(__doc__)
    for pair in argv[2:]:
        shot, gold = pair.split('=', 1)
        w, h, a = load(shot)
        gw, gh, b = load(argv[1] + '/' + gold)
        if (w, h) != (gw, gh):
            print(f'{shot}: {w} x {h} pixels, {gold} has {gw} x {gh}')
            return 1
        n = differing(a, b, w, h)
        print(f'{shot}: {n} of {w * h} pixels differ from {gold} by more than {TOLERANCE}/255')
        if n > DIFFERING_FRACTION * w * h:
            return 1
    return 0


if __name__ == '__main__':
    sys.exit(main(sys.argv))
