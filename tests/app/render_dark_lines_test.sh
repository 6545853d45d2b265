#!/usr/bin/env bash
# The AM phantom at rest, 640x960 from the front (render's default camera):
# with smooth shading under 0.2% of the body's pixels are darker than 60% of
# their 5x5 median (tests/bench/dark_lines.py), the GPU image agreeing with
# the CPU reference (--verify); face shading, for contrast, over 1%.
# Skipped (77) without numpy and PIL.
set -euo pipefail
bin=$1 src=$2 work=$3 python=$4
"$python" -c 'import numpy, PIL' 2>/dev/null || exit 77
rm -rf "$work" && mkdir -p "$work"
for shading in smooth faces; do
  "$bin" render "$src/assets/icrp110_am.nii.gz" --organs "$src/assets/icrp110_am_organs.dat" --size 640x960 \
    --shading "$shading" --verify -o "$work/$shading.png"
done
"$python" "$src/tests/bench/dark_lines.py" "$work/smooth.png" --max 0.002
! "$python" "$src/tests/bench/dark_lines.py" "$work/faces.png" --max 0.01
