#!/usr/bin/env bash
# Frame times of `voxmorph view` while the user drags: the adult female at
# 1280x720 (the view is the window less the 360-pixel panel: 920x720), the
# head turned 40 degrees about z with the gizmo over 40 frames, under Xvfb.
# Prints the per-frame split (deformation, ray casting, UI, present) of the
# dragging frames. The peer measured in the same run is
# raycast_bench's AF rest frame at the drag resolution (the ray caster alone:
# positions to image, read back).
# Usage: tests/bench/viewer_frames.sh [build dir]   (default build/release;
# builds raycast_bench there first)
set -euo pipefail
cd "$(dirname "$0")/../.."
bin=${1:-build/release}/voxmorph
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
xvfb-run -a -s "-screen 0 1600x900x24" "$bin" view assets/icrp110_af.nii.gz --organs assets/icrp110_af_organs.dat \
  --script tests/bench/data/viewer_drag_af.json --frame-log "$work/frames.csv" --no-vsync 2>/dev/null
python3 - "$work/frames.csv" <<'PY'
import csv, statistics, sys
rows = [r for r in csv.DictReader(open(sys.argv[1]))]
drag = [r for r in rows if float(r['deform_ms']) > 0 and int(r['render_width']) < 920]
still = [r for r in rows if int(r['render_width']) == 920]
def med(rs, k): return statistics.median(float(r[k]) for r in rs)
print(f"dragging frames: {len(drag)} at {drag[0]['render_width']}x{drag[0]['render_height']}")
for k in ('deform_ms', 'raycast_ms', 'ui_ms', 'present_ms', 'total_ms'):
    print(f"  median {k}: {med(drag, k):.1f}")
print(f"  frames per second (median frame): {1000.0 / med(drag, 'total_ms'):.1f}")
if still: print(f"still frames: {len(still)} at 920x720, median ray cast {med(still, 'raycast_ms'):.1f} ms, total {med(still, 'total_ms'):.1f} ms")
PY
cmake --build "${1:-build/release}" --target raycast_bench >/dev/null
VOXMORPH_BENCH_SIZE=460x360 "${1:-build/release}/bench/raycast_bench" --benchmark_filter='Raycast/af/rest/iter' 2>/dev/null |
  grep Raycast | sed 's/^/peer: /'
