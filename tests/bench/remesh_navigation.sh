#!/usr/bin/env bash
# Navigation between resolutions (issue 37, item 4): a grid meshed at l0,
# that mesh remeshed to each coarser or finer target without the grid (the
# interfaces from its own interface facets), against meshing the grid at
# each target directly: the peer, in the same run. One process per run under
# /usr/bin/time; prints a row per run: process CPU s (user + sys), wall,
# peak RSS, tets, min dihedral, tets under 10 and 15 degrees, topology
# (against the run's input: the grid, or the l0 mesh, itself checked against
# the grid) and the largest interface Hausdorff distance over l.
# Usage: tests/bench/remesh_navigation.sh WORKDIR [l0 [targets...]]
#   (default l0 = 8, targets 16 4; grid and organs from VOX_GRID and
#   VOX_ORGANS, default the AM; voxmorph from VOX_BIN, default
#   build/release/voxmorph). Outputs and reports stay in WORKDIR.
set -euo pipefail
cd "$(dirname "$0")/../.."
[ $# -ge 1 ] || { echo "usage: $0 WORKDIR [l0 [targets...]]" >&2; exit 2; }
work=$1
l0=${2:-8}
shift $(( $# >= 2 ? 2 : 1 ))
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=(16 4)
bin=${VOX_BIN:-build/release/voxmorph}
grid=${VOX_GRID:-assets/icrp110_am.nii.gz}
organs=${VOX_ORGANS:-assets/icrp110_am_organs.dat}
mkdir -p "$work"

# run NAME voxmorph-arguments...: the report in NAME.json, time's in NAME.time
run() {
  local name=$1
  shift
  /usr/bin/time -v -o "$work/$name.time" "$bin" "$@" --organs "$organs" -q \
    -o "$work/$name.mesh" --report "$work/$name.json" >/dev/null
  row "$name"
}

row() {
  python3 - "$work/$1" <<'PY'
import json, re, sys
base = sys.argv[1]
t = open(base + '.time').read()
def field(name): return re.search(re.escape(name) + r': (.*)', t).group(1).strip()
cpu = float(field('User time (seconds)')) + float(field('System time (seconds)'))
wall = field('Elapsed (wall clock) time (h:mm:ss or m:ss)')
rss = int(field('Maximum resident set size (kbytes)')) / 1024
r = json.load(open(base + '.json'))
d = [l['interface_distance_over_l']['hausdorff'] for l in r['labels'] if 'interface_distance_over_l' in l]
topo = 'exact' if r['topology']['preserved'] else '%d differences' % len(r['topology']['differences'])
print(f"| {base.rsplit('/', 1)[-1]} | {r['target_edge_length_mm']:g} mm | {cpu:.1f} s | {wall} | {rss:.0f} MB | "
      f"{r['tets']['output']:,} | {r['dihedral_degrees']['min']:.2f} deg | {r['tets_under_10_degrees']} | "
      f"{r['tets_under_15_degrees']} | {topo} | {max(d) if d else float('nan'):.3f} |", flush=True)
PY
}

echo "$(date -u +%FT%TZ) $(uname -n), load average $(cut -d' ' -f1-3 /proc/loadavg), $(git rev-parse --short HEAD)"
echo "| run | l | process CPU | wall | peak RSS | tets | min dihedral | < 10 deg | < 15 deg | topology | max Hausdorff / l |"
echo "|---|---|---|---|---|---|---|---|---|---|---|"
# An l0 mesh already in WORKDIR (with its .json and .time) is reused.
if [ -f "$work/grid_$l0.mesh" ] && [ -f "$work/grid_$l0.json" ] && [ -f "$work/grid_$l0.time" ]; then
  row "grid_$l0"
else
  run "grid_$l0" mesh "$grid" -l "$l0"
fi
for l in "${targets[@]}"; do
  run "nav_${l0}_to_$l" remesh "$work/grid_$l0.mesh" -l "$l"
  run "grid_$l" mesh "$grid" -l "$l"
done
echo "$(date -u +%FT%TZ) load average $(cut -d' ' -f1-3 /proc/loadavg)"
