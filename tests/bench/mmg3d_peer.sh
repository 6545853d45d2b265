#!/usr/bin/env bash
# MMG3D (MmgTools/mmg, built outside the tree) against `voxmorph remesh` on
# the same input and target l, in one run (issue 37's peer): mmg3d_O3 with
# `-hsiz l -hausd 0.5l` (the remesher's interface bound, 0.5 l), one process
# each under /usr/bin/time, on
#   am:     the AM meshed from the grid at l by `voxmorph mesh` (Medit .mesh);
#   organs: an exuded CGAL Mesh_3 mesh of a few organs of the AM (gall
#           bladder, kidneys, liver, pancreas, spleen; every other label
#           cleared, cropped to them with a 2-voxel margin), its domain tets.
# Both outputs are measured by remesh_bench's BM_PeerOutput (the same code for
# both: tets, min dihedral, tets under 15, 10 and 5 degrees, topology against
# the grid, or against the Mesh_3 mesh). Prints one table row per run.
# Usage: tests/bench/mmg3d_peer.sh MMG3D_BINARY WORKDIR [l]   (default l = 8 mm;
#   voxmorph and remesh_bench from VOX_BUILD, default build/release; inputs
#   already in WORKDIR are reused: am_input.mesh, organs_input.mesh).
# Not run by ctest (MMG3D is not a dependency).
set -euo pipefail
cd "$(dirname "$0")/../.."
[ $# -ge 2 ] || { echo "usage: $0 MMG3D_BINARY WORKDIR [l]" >&2; exit 2; }
mmg=$(realpath "$1")
work=$2
l=${3:-8}
build=${VOX_BUILD:-build/release}
hausd=$(python3 -c "print($l / 2)")
organs=assets/icrp110_am_organs.dat
mkdir -p "$work"

cpu() {  # process CPU s (user + sys) from a `time -v` file
  python3 - "$1" <<'PY'
import re, sys
t = open(sys.argv[1]).read()
f = lambda n: float(re.search(re.escape(n) + r': (.*)', t).group(1))
print(f"{f('User time (seconds)') + f('System time (seconds)'):.1f} s")
PY
}

# measure CASE-ENV... -- MESH: remesh_bench's counters for MESH as a row tail
measure() {
  local out=$1
  shift
  env "$@" VOX_REMESH_PEER_OUTPUT="$out" "$build/bench/remesh_bench" --benchmark_filter=BM_PeerOutput \
    --benchmark_format=json --benchmark_out="$out.bench.json" >/dev/null 2>"$out.bench.log"
  python3 - "$out.bench.json" <<'PY'
import json, sys
b = json.load(open(sys.argv[1]))["benchmarks"][0]
print(f"{int(b['tets']):,} | {b['min_dihedral']:.2f} deg | {int(b['under_10'])} | {int(b['under_15'])} | "
      f"{int(b['under_5'])} | {int(b['topology_differences'])} | {int(b['inverted'])}")
PY
}

# peers NAME CASE-ENV...: both remeshers on WORKDIR/NAME_input.mesh, a row each
peers() {
  local name=$1
  shift
  local in="$work/${name}_input.mesh"
  if /usr/bin/time -v -o "$work/${name}_mmg.time" "$mmg" -in "$in" -out "$work/${name}_mmg.mesh" -hsiz "$l" \
      -hausd "$hausd" >"$work/${name}_mmg.log" 2>&1; then
    echo "| $name | MMG3D \`-hsiz $l -hausd $hausd\` | $(cpu "$work/${name}_mmg.time") | $(measure "$work/${name}_mmg.mesh" "$@") |"
  else
    echo "| $name | MMG3D \`-hsiz $l -hausd $hausd\` | failed: $(grep -m1 -i -E 'error|too bad' "$work/${name}_mmg.log" || tail -n1 "$work/${name}_mmg.log") |"
  fi
  /usr/bin/time -v -o "$work/${name}_vox.time" "$build/voxmorph" remesh "$in" -l "$l" --organs "$organs" -q \
    --no-distance -o "$work/${name}_vox.mesh" --report "$work/${name}_vox.json" >/dev/null
  echo "| $name | voxmorph remesh \`-l $l\` | $(cpu "$work/${name}_vox.time") | $(measure "$work/${name}_vox.mesh" "$@") |"
}

VOX_BUILD="$build" tests/bench/remesh_organs_input.sh "$work" "$l"
if [ ! -f "$work/am_input.mesh" ]; then
  "$build/voxmorph" mesh assets/icrp110_am.nii.gz -l "$l" -q -o "$work/am_input.mesh" --no-distance \
    --report "$work/am_input.json" >/dev/null
fi

echo "$(date -u +%FT%TZ) $(uname -n), load average $(cut -d' ' -f1-3 /proc/loadavg), $(git rev-parse --short HEAD)"
echo "| input | remesher | process CPU | tets | min dihedral | < 10 deg | < 15 deg | < 5 deg | topology differences | inverted |"
echo "|---|---|---|---|---|---|---|---|---|---|"
peers organs VOX_REMESH_GRID="$work/organs.nii.gz" VOX_REMESH_L="$l" VOX_REMESH_INPUT=mesh3 \
  VOX_REMESH_MESH3_FILE="$work/organs_mesh3.mesh"
peers am VOX_REMESH_L="$l"
grep -m1 -o 'MMG3D, Release [^ ]*' "$work/am_mmg.log" || true
echo "$(date -u +%FT%TZ) load average $(cut -d' ' -f1-3 /proc/loadavg)"
