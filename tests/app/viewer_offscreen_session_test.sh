#!/usr/bin/env bash
# The scripted session of viewer_session without a window: `view --offscreen`
# with no DISPLAY (no X server, no Xvfb) on lavapipe, the steps up to the
# redo (tests/app/data/viewer_offscreen_session.json: the export is the
# windowed session's). Checks: the screenshots match the windowed session's
# golden images within the same tolerance (tests/app/golden_png.py), and
# undo and redo give the same images byte for byte; the window screenshot
# has the window's size, the panels drawn left of the view and the ray-cast
# view right of them (the cage hidden for it); the frame log has a row per rendered frame. Without
# --script, --offscreen is a usage error (exit 2, one line); a missing
# screenshot directory is refused before the pre-processing (exit 1, one line).
set -euo pipefail
bin=$1 src=$2 work=$3
rm -rf "$work" && mkdir -p "$work"
cd "$work"
env -u DISPLAY -u WAYLAND_DISPLAY "$bin" view "$src/assets/icrp110_am.nii.gz" --organs "$src/assets/icrp110_am_organs.dat" \
  --pose "$src/assets/viewer/am_right_arm_free.json" --script "$src/tests/app/data/viewer_offscreen_session.json" \
  --screenshot-dir "$work" --frame-log frames.csv --offscreen 2> >(tee session.log >&2)
cmp rest.png undone.png
! cmp -s posed_cut.png posed_cut_slid.png  # the plane's handle moved the cut
cmp posed_cut_slid.png redone.png
python3 "$src/tests/app/golden_png.py" "$src/assets/golden" rest.png=viewer_am_rest.png posed.png=viewer_am_right_arm_45.png \
  posed_cut.png=viewer_am_right_arm_45_cut.png
python3 - "$src/tests/app" <<'PY'
import csv, sys
sys.path.insert(0, sys.argv[1])
from golden_png import load, differing
# The window: 960 x 540 (the script's size), the 360-pixel panel column left
# of the 600 x 540 view. With the cage hidden and no selection yet, the view
# columns above the export box (bottom right) are the ray-cast image
# (rest.png, blitted at its size).
w, h, window = load('rest_window.png')
vw, vh, view = load('rest.png')
assert (w, h) == (960, 540) and (vw, vh) == (600, 540), (w, h, vw, vh)
assert load('posed_window.png')[:2] == (960, 540)
shifted = [bytearray(3 * 360) + row for row in view]
over = differing(window, shifted, w, 400, 360)
print(f'rest_window.png: {over} of {vw * 400} view pixels above the export box differ from rest.png')
assert over == 0
panel = {bytes(window[y][3 * x:3 * x + 3]) for y in range(h) for x in range(360)}
print(f'rest_window.png: {len(panel)} colours in the panel column')
assert len(panel) > 10
rows = list(csv.DictReader(open('frames.csv')))
print(f'frames.csv: {len(rows)} rendered frames')
assert len(rows) >= 20 and all(float(r['total_ms']) > 0 for r in rows)
PY
set +e
out=$(env -u DISPLAY -u WAYLAND_DISPLAY "$bin" view "$src/assets/icrp110_am.nii.gz" --offscreen 2>&1)
rc=$?
set -e
echo "$out"
test "$rc" -eq 2 && test "$(echo "$out" | wc -l)" -eq 1 && echo "$out" | grep -q -- '--offscreen'
# A screenshot directory that does not exist: refused at the start with
# one line (exit 1), before the pre-processing, nothing written.
set +e
out=$(env -u DISPLAY -u WAYLAND_DISPLAY "$bin" view "$src/assets/icrp110_am.nii.gz" --organs "$src/assets/icrp110_am_organs.dat" \
  --script "$src/tests/app/data/viewer_offscreen_session.json" --screenshot-dir "$work/missing" --offscreen 2>&1)
rc=$?
set -e
echo "$out"
test "$rc" -eq 1 && test "$(echo "$out" | wc -l)" -eq 1 && echo "$out" | grep -q 'missing: the screenshot directory does not exist'
! echo "$out" | grep -q 'pre-processing'
test ! -e "$work/missing"
echo "viewer offscreen session: passed"
