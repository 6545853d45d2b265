#!/usr/bin/env bash
# The joint pose solved on the articulated transfer mesh in the viewer
# (`view --offscreen`, no display; tests/app/data/viewer_articulated_session.json)
# on the synthetic skeleton figure, its right elbow bent 90 degrees: the
# solve's 17 steps with no tet inverted; its last step shows the silhouette
# the cage pipeline's frame of the same pose shows (cage.png) more closely than
# its first step does; a step between them is neither; a joint turned after
# the solve shows the cage pipeline's frame again, not the stale solve. A
# step shown before any solve, or an index of 0, is refused with one line.
set -euo pipefail
bin=$1 src=$2 work=$3 python=$4
rm -rf "$work" && mkdir -p "$work"
cd "$work"
"$bin" synth skeleton --size 96 -o skeleton.nii.gz --organs skeleton.dat
echo '{"joints": {"right_elbow": {"flexion": 90}}}' > elbow.json
view=(view skeleton.nii.gz --organs skeleton.dat --pose elbow.json --offscreen --screenshot-dir "$work")
env -u DISPLAY -u WAYLAND_DISPLAY "$bin" "${view[@]}" --script "$src/tests/app/data/viewer_articulated_session.json" 2> >(tee session.log >&2)
grep -q '^view: articulated: 17 steps, 0 tets inverted in the posed mesh' session.log
"$python" - "$src/tests/app" <<'PY'
import sys
sys.path.insert(0, sys.argv[1])
from golden_png import load
def body(path):
    w, h, rows = load(path)
    bg = bytes(rows[0][0:3])
    return {(x, y) for y in range(h) for x in range(w) if bytes(rows[y][3 * x:3 * x + 3]) != bg}
cage, first, middle, last, edited = (body(f + '.png') for f in ('cage', 'first', 'middle', 'last', 'edited'))
d = lambda a, b: len(a ^ b)
print(f'silhouettes differing (pixels): last/cage {d(last, cage)}, first/last {d(first, last)}, '
      f'middle/first {d(middle, first)}, middle/last {d(middle, last)}, edited/last {d(edited, last)}, edited/cage {d(edited, cage)}')
assert len(last) > 20000
assert 2 * d(last, cage) < d(first, last), 'the last step is the pose'
assert d(middle, first) > 200 and d(middle, last) > 200, 'a step between them'
assert d(edited, last) > 2 * d(last, cage), 'the turned joint does not show the stale solve'
PY
for script in '{"steps": [{"step": "articulated_step", "index": 2}]}' '{"steps": [{"step": "articulated_step", "index": 0}]}'; do
  echo "$script" > bad.json
  set +e
  out=$(env -u DISPLAY -u WAYLAND_DISPLAY "$bin" "${view[@]}" --script bad.json 2>&1)
  rc=$?
  set -e
  echo "$out" | tail -n 1
  test "$rc" -eq 1 && test "$(echo "$out" | grep -c 'voxmorph: error: ')" -eq 1 && echo "$out" | grep -q 'articulated_step'
done
