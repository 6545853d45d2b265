#!/usr/bin/env python3
"""Checks that every project #include goes the way the layers allow.

    include_direction.py SOURCE_DIR [--plant FILE:HEADER ...]

Reads the `#include "..."` lines of every C++ and GLSL file under the
library's folders, maps the including file and the included header to their
layers (LAYERS: the first matching path prefix wins) and reports each include
that ALLOWED does not list, one line each: `FILE:LINE: LAYER includes
HEADER (LAYER)`. Exit 0 when none, 1 otherwise. `--plant` adds an include
that is not in the tree (the check's own test plants a wrong-way one).
docs/ARCHITECTURE.md draws the same table.
"""
import os
import re
import sys

# Path prefix -> layer, most specific first.
LAYERS = [
    ("geometry/deform/run/", "run"),
    ("geometry/deform/", "deform"),
    ("geometry/skeleton/", "skeleton"),
    ("geometry/remesh/", "remesh"),
    ("geometry/render/", "render"),
    ("geometry/raster/", "raster"),
    ("geometry/io/", "io"),
    ("geometry/", "core"),
    ("shaders/shared/", "interface"),
    ("shaders/", "shaders"),
    ("gpu/", "gpu"),
    ("app/", "app"),
    ("python/", "python"),
    ("tests/", "tests"),
]

# What each layer may include besides itself (interface: the structs and
# binding numbers C++ shares with the GLSL kernels). Below the run of a
# deformation nothing knows of Vulkan; gpu/ provides kernels and engines and
# knows nothing of deformation, anatomy or files.
ALLOWED = {
    "core": set(),
    "io": {"core"},
    "raster": {"core", "interface"},
    "render": {"core", "raster", "interface"},
    "remesh": {"core"},
    "skeleton": {"core"},
    "deform": {"core", "io", "raster", "skeleton"},
    "run": {"core", "io", "raster", "skeleton", "deform"},
    "interface": set(),
    "shaders": {"interface"},
    "gpu": {"core", "raster", "render", "interface", "shaders"},
    "app": {"core", "io", "raster", "render", "remesh", "skeleton", "deform", "run", "gpu", "interface", "shaders"},
    "python": {"core", "io", "raster", "render", "remesh", "skeleton", "deform", "run", "gpu", "interface", "shaders"},
    "tests": {layer for _, layer in LAYERS},
}

SCANNED = ("geometry", "gpu", "shaders", "app", "python")
SUFFIXES = (".h", ".cpp", ".comp", ".glsl")
INCLUDE = re.compile(r'^\s*#\s*include\s+"([^"]+)"')


def layer_of(path):
    for prefix, layer in LAYERS:
        if path.startswith(prefix):
            return layer
    return None


def includes(root):
    for top in SCANNED:
        for directory, _, files in os.walk(os.path.join(root, top)):
            for name in sorted(files):
                if not name.endswith(SUFFIXES):
                    continue
                path = os.path.join(directory, name)
                rel = os.path.relpath(path, root)
                with open(path, encoding="utf-8", errors="replace") as f:
                    for number, line in enumerate(f, 1):
                        m = INCLUDE.match(line)
                        if m:
                            yield rel, number, m.group(1)


def resolve(including, header, root):
    """The header's path from the source root (project includes are written
    from the root; GLSL and a few local ones beside the including file)."""
    if layer_of(header) is not None and os.path.exists(os.path.join(root, header)):
        return header
    beside = os.path.normpath(os.path.join(os.path.dirname(including), header))
    if os.path.exists(os.path.join(root, beside)):
        return beside
    return header


def main(argv):
    args = argv[1:]
    if not args:
        print(__doc__.strip().splitlines()[2].strip(), file=sys.stderr)
        return 2
    root, planted = args[0], []
    rest = args[1:]
    while rest:
        if rest[0] != "--plant" or len(rest) < 2 or ":" not in rest[1]:
            print("usage: include_direction.py SOURCE_DIR [--plant FILE:HEADER ...]", file=sys.stderr)
            return 2
        file, header = rest[1].split(":", 1)
        planted.append((file, 0, header))
        rest = rest[2:]

    faults, count = [], 0
    for including, number, header in list(includes(root)) + planted:
        count += 1
        source = layer_of(including)
        target_path = resolve(including, header, root)
        target = layer_of(target_path)
        if source is None or target is None or target == source:
            continue
        if target not in ALLOWED[source]:
            faults.append(f"{including}:{number}: {source} includes {target_path} ({target})")
    for fault in faults:
        print(fault)
    if faults:
        print(f"include_direction: {len(faults)} of {count} includes go against the layers", file=sys.stderr)
        return 1
    print(f"include_direction: {count} includes, every one along the layers")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
