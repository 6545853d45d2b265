#!/usr/bin/env bash
# The interface Hausdorff bound (issue 37: at most 0.5 l), before and after,
# in one run: two voxmorph binaries (a build without the bound, and one with
# it, or the same binary with `--hausdorff 0` as BEFORE="BIN --hausdorff 0")
# on the same inputs at the same l, one process per run under
# /usr/bin/time, each with the report's interface distances. Inputs:
#   organs:    the five-organ Mesh_3 mesh (tests/bench/remesh_organs_input.sh),
#              `voxmorph remesh`;
#   crop:      the AM's voxels from (60, 20, 100), 96 x 64 x 40, `voxmorph mesh`;
#   spheres, junctions: `voxmorph synth spheres|junctions --size 96`, `mesh`;
#   and with VOX_WHOLE="am af" the whole AM and AF grids, `mesh`.
# Prints a row per run: process CPU s (user + sys), peak RSS, tets, min
# dihedral, tets under 10 and 15 degrees, topology against the input, the
# largest interface Hausdorff distance over the labels in units of l (label,
# direction), and the labels over 0.5 l.
# Usage: tests/bench/remesh_interface_bound.sh BEFORE AFTER WORKDIR [l]
#   (default l = 8 mm; remesh_bench for the organs from VOX_BUILD, default
#   build/release). Inputs already in WORKDIR are reused.
set -euo pipefail
cd "$(dirname "$0")/../.."
[ $# -ge 3 ] || { echo "usage: $0 BEFORE AFTER WORKDIR [l]" >&2; exit 2; }
before=$1
after=$2
work=$3
l=${4:-8}
mkdir -p "$work"

tests/bench/remesh_organs_input.sh "$work" "$l"
[ -f "$work/crop.nii.gz" ] || /usr/bin/python3 - "$work/crop.nii.gz" <<'PY'
import nibabel as nib, sys
nib.save(nib.load('assets/icrp110_am.nii.gz').slicer[60:156, 20:84, 100:140], sys.argv[1])
PY
[ -f "$work/spheres.nii.gz" ] || ${after%% *} synth spheres --size 96 -o "$work/spheres.nii.gz"
[ -f "$work/junctions.nii.gz" ] || ${after%% *} synth junctions --size 96 -o "$work/junctions.nii.gz"

# run NAME BUILD COMMAND INPUT [organs]: one row
run() {
  local name=$1 build=$2 command=$3 input=$4 organs=${5:-}
  local bin=$before
  [ "$build" = after ] && bin=$after
  local out="$work/${name}_$build"
  # shellcheck disable=SC2086  # BEFORE and AFTER may carry options
  /usr/bin/time -v -o "$out.time" $bin "$command" "$input" -l "$l" ${organs:+--organs "$organs"} -q \
    -o "$out.mesh" --report "$out.json" >/dev/null
  python3 - "$out" "$name" "$build" <<'PY'
import json, re, sys
out, name, build = sys.argv[1:4]
t = open(out + '.time').read()
f = lambda n: re.search(re.escape(n) + r': (.*)', t).group(1)
cpu = float(f('User time (seconds)')) + float(f('System time (seconds)'))
r = json.load(open(out + '.json'))
worst, where, over = 0.0, '', 0
for x in r['labels']:
    d = x['interface_distance_over_l']
    over += d['hausdorff'] > 0.5
    for way in ('input_to_output', 'output_to_input'):
        if d[way] > worst:
            worst, where = d[way], f"{x['label']}, {way.replace('_', ' ')}"
topo = 'exact' if r['topology']['preserved'] else f"{len(r['topology']['differences'])} differences"
print(f"| {name} | {build} | {cpu:.1f} s | {int(f('Maximum resident set size (kbytes)')) // 1024:,} MB | "
      f"{r['tets']['output']:,} | {r['dihedral_degrees']['min']:.2f} | {r['tets_under_10_degrees']} | "
      f"{r['tets_under_15_degrees']} | {topo} | {worst:.3f} ({where}) | {over} of {len(r['labels'])} |")
PY
}

organs=assets/icrp110_am_organs.dat
echo "$(date -u +%FT%TZ) $(uname -n), load average $(cut -d' ' -f1-3 /proc/loadavg), $(git rev-parse --short HEAD), l = $l mm"
echo "| input | build | process CPU | peak RSS | tets | min dihedral | < 10 deg | < 15 deg | topology | largest Hausdorff / l (label, direction) | labels over 0.5 l |"
echo "|---|---|---|---|---|---|---|---|---|---|---|"
for build in before after; do run organs "$build" remesh "$work/organs_input.mesh" "$organs"; done
for build in before after; do run crop "$build" mesh "$work/crop.nii.gz" "$organs"; done
for build in before after; do run spheres "$build" mesh "$work/spheres.nii.gz"; done
for build in before after; do run junctions "$build" mesh "$work/junctions.nii.gz"; done
for whole in ${VOX_WHOLE:-}; do
  for build in before after; do
    run "$whole" "$build" mesh "assets/icrp110_$whole.nii.gz" "assets/icrp110_${whole}_organs.dat"
  done
done
echo "$(date -u +%FT%TZ) load average $(cut -d' ' -f1-3 /proc/loadavg)"
