#!/usr/bin/env bash
# A fuzzing campaign measured in CPU time: each harness of build/fuzz runs
# from its working corpus (seeded with tests/fuzz/corpus/<reader>) until the
# fuzzing process has used its CPU budget (user + sys, from /proc), so that a
# campaign on a loaded machine (run it under `nice`) still gives every
# harness the time it is due. Grid and tet-mesh readers get the long budget.
#
#   tests/fuzz/campaign.sh [long-minutes] [short-minutes] [lanes] [harness...]
#
# Defaults: 30, 10, 2 lanes, every harness. One row per harness is appended
# to build/fuzz/campaign.tsv (harness, CPU s, wall s, executions, corpus
# files, finding); a finding is kept under build/fuzz/findings/ and makes
# the script exit 1.
set -uo pipefail
cd "$(dirname "$0")/../.."

long=${1:-30}
short=${2:-10}
lanes=${3:-2}
shift $(($# < 3 ? $# : 3))
names=("$@")
if [ ${#names[@]} -eq 0 ]; then
  for b in build/fuzz/tests/fuzz/fuzz_*; do names+=("$(basename "$b" | sed 's/^fuzz_//')"); done
fi
[ ${#names[@]} -gt 0 ] || { echo "campaign: no harness under build/fuzz (./run fuzz 1 builds them)" >&2; exit 2; }
mkdir -p build/fuzz/findings
table=build/fuzz/campaign.tsv
[ -f "$table" ] || printf 'harness\tcpu_s\twall_s\texecutions\tcorpus_files\tfinding\n' >"$table"
ticks=$(getconf CLK_TCK)

budget() {
  case "$1" in
    nifti | sizing_grid | metaimage | nrrd | inr | medit | meshb | vtu | gmsh) echo $((long * 60)) ;;
    *) echo $((short * 60)) ;;
  esac
}

cpu_seconds() {  # user + sys of a running process, whole seconds
  awk -v t="$ticks" '{ print int(($14 + $15) / t) }' "/proc/$1/stat" 2>/dev/null || echo -1
}

run_one() {
  local n=$1 limit work log start pid used=0 rc finding=none
  limit=$(budget "$n")
  work=build/fuzz/corpus/$n
  log=build/fuzz/findings/$n.campaign.log
  mkdir -p "$work"
  start=$(date +%s)
  build/fuzz/tests/fuzz/fuzz_"$n" -rss_limit_mb=2048 -timeout=20 -print_final_stats=1 \
    -artifact_prefix=build/fuzz/findings/"$n"- "$work" tests/fuzz/corpus/"$n" >"$log" 2>&1 &
  pid=$!
  while kill -0 "$pid" 2>/dev/null; do
    used=$(cpu_seconds "$pid")
    [ "$used" -ge "$limit" ] && { kill -INT "$pid"; break; }
    sleep 5
  done
  wait "$pid"
  rc=$?
  # A run that ended before its budget without being interrupted found something.
  if [ "$used" -lt "$limit" ] && [ $rc -ne 0 ]; then finding="see $log"; fi
  local execs files
  execs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' | tail -1)
  files=$(find "$work" -type f | wc -l)
  printf '%s\t%s\t%s\t%s\t%s\t%s\n' "$n" "$used" $(($(date +%s) - start)) "${execs:-0}" "$files" "$finding" >>"$table"
  [ "$finding" = none ]
}

# Longest budgets first, spread over the lanes.
mapfile -t ordered < <(for n in "${names[@]}"; do echo "$(budget "$n") $n"; done | sort -rn | awk '{ print $2 }')
failed=0
for ((lane = 0; lane < lanes; ++lane)); do
  (
    status=0
    for ((k = lane; k < ${#ordered[@]}; k += lanes)); do run_one "${ordered[$k]}" || status=1; done
    exit $status
  ) &
done
for job in $(jobs -p); do wait "$job" || failed=1; done
column -t -s $'\t' "$table"
exit $failed
