#!/usr/bin/env bash
# The posture-study workflow (workflow/Snakefile) on a small study: two
# synthetic stick figures (48 and 40 voxels tall) x two poses, through
# snakemake with 2 cores. Checks: the Slurm profile's dry run lists one job
# per row with its resources; the summary CSV has 4 rows that pandas reads,
# with the inputs' provenance digests and the projected areas; the contact
# sheet holds the 4 tiles; a second run executes nothing; removing one row's
# output reruns that row alone (and the summary); a job killed mid-way
# (SIGKILL) leaves none of its row's outputs and no temporary files; a bad
# study file is one error naming the file, the line and the fault. Each
# phantom is prepared once (voxmorph prepare) before its rows, which deform
# with it; removing a row's output does not prepare again.
# Exit 77 (skipped) when snakemake is not installed.
set -euo pipefail
bin=$1 src=$2 work=$3 python=$4
command -v snakemake >/dev/null || { echo "snakemake not installed (./run build installs it)"; exit 77; }
rm -rf "$work" && mkdir -p "$work"
cd "$work"
fail() { echo "FAIL: $*" >&2; exit 1; }
"$bin" synth stick --size 48 -o tall.nii.gz --organs tall.dat >/dev/null
"$bin" synth stick --size 40 -o short.mha --organs short.dat >/dev/null
{
  printf 'phantom\tgrid\torgans\tpose\toptions\toutput\n'
  for ph in tall:tall.nii.gz short:short.mha; do
    for pose in stick_right_arm_out_30 stick_head_turned_30; do
      printf '%s\t%s\t%s.dat\t%s\t--preserve-volumes --force\tout/%s/%s\n' "${ph%%:*}" "${ph#*:}" "${ph%%:*}" \
        "$src/tests/workflow/data/$pose.json" "${ph%%:*}" "$pose"
    done
  done
} > study.tsv
smk=(snakemake -s "$src/workflow/Snakefile" --config study=study.tsv voxmorph="$bin")
rows=(out/tall/stick_right_arm_out_30 out/tall/stick_head_turned_30 out/short/stick_right_arm_out_30 out/short/stick_head_turned_30)
files=(posed.nii.gz report.json report.csv plots.png front.png side.png)

# Slurm profile, dry run: one posture job per row, with its resources.
"${smk[@]}" --profile "$src/workflow/profiles/slurm" -n > dryrun.log 2>&1 || { cat dryrun.log; fail "dry run"; }
test "$(grep -c '^rule posture:' dryrun.log)" -eq 4 || fail "dry run lists $(grep -c '^rule posture:' dryrun.log) posture jobs, not 4"
test "$(grep -c '^rule prepare:' dryrun.log)" -eq 2 || fail "dry run lists $(grep -c '^rule prepare:' dryrun.log) prepare jobs, not 2 (one per phantom)"
test "$(grep -c 'resources: mem_mb=4096, .*cpus_per_task=2, runtime=60, gpus=0' dryrun.log)" -eq 6 || fail "resources missing from the dry run"

# First run: every row, the summary and the contact sheet.
"${smk[@]}" --cores 2 > run1.log 2>&1 || { cat run1.log; fail "first run"; }
for r in "${rows[@]}"; do for f in "${files[@]}"; do test -s "$r/$f" || fail "$r/$f missing"; done; done
# Each phantom prepared once, its rows deformed with it.
for ph in tall short; do test -s "out/prepared/$ph.vxprep" || fail "out/prepared/$ph.vxprep missing"; done
test "$(grep -c '^rule prepare:' run1.log)" -eq 2 || fail "the first run prepared $(grep -c '^rule prepare:' run1.log) times, not 2"
for r in "${rows[@]}"; do
  grep -q '"role": "prepared"' "$r/report.json" || fail "$r did not deform with the prepared state (its report's inputs)"
done
"$python" - "$(sha256sum tall.nii.gz | cut -c1-64)" "$(sha256sum short.dat | cut -c1-64)" <<'PY'
import json
import sys
import pandas as pd
from PIL import Image
tall_grid, short_organs = sys.argv[1:3]
s = pd.read_csv("out/summary.csv")
assert len(s) == 4, len(s)
assert list(s["phantom"]) == ["tall", "tall", "short", "short"], list(s["phantom"])
assert list(s["pose"]) == ["stick_right_arm_out_30", "stick_head_turned_30"] * 2, list(s["pose"])
assert (s[s.phantom == "tall"]["grid_sha256"] == tall_grid).all()
assert (s[s.phantom == "short"]["organs_sha256"] == short_organs).all()
assert s["pose_sha256"].str.len().eq(64).all()
# Voxels of 2 mm: the figures stand 45 and 38 voxels tall.
assert list(s["height_mm_rest"]) == [90.0, 90.0, 76.0, 76.0], list(s["height_mm_rest"])
assert (s["front_area_mm2_rest"] > 0).all() and (s["side_area_mm2"] > 0).all()
# The arm swung out widens the body seen from the top.
arm = s[s.pose == "stick_right_arm_out_30"]
assert (arm["top_area_mm2"] > arm["top_area_mm2_rest"]).all(), arm[["top_area_mm2", "top_area_mm2_rest"]]
assert (s["mass_g:1:Trunk"] > 0).all()
o = pd.read_csv("out/summary_organs.csv")
labels = sum(len(json.load(open(f"{r}/report.json"))["labels"]) for r in s["output"])
assert len(o) == labels and labels >= 4 * 7, (len(o), labels)
sheet = Image.open("out/contact_sheet.png")
view = Image.open("out/tall/stick_head_turned_30/front.png")
assert sheet.width > 8 * view.width and sheet.height > view.height, (sheet.size, view.size)
print("summary: 4 rows,", len(s.columns), "columns")
PY

# Second run: nothing to do, nothing touched.
stamp() { find out -type f -printf '%p %T@\n' | sort; }
before=$(stamp)
"${smk[@]}" --cores 2 > run2.log 2>&1 || { cat run2.log; fail "second run"; }
grep -q "Nothing to be done" run2.log || { cat run2.log; fail "second run executed jobs"; }
test "$before" = "$(stamp)" || fail "second run changed files"

# One row's output removed: that row alone runs again, then the summary.
rm out/short/stick_head_turned_30/report.json
"${smk[@]}" --cores 2 > run3.log 2>&1 || { cat run3.log; fail "third run"; }
grep -Eq '^posture +1 ' run3.log || { cat run3.log; fail "the third run did not run exactly one row"; }
grep -q '^rule prepare:' run3.log && { cat run3.log; fail "the third run prepared again"; }
after=$(stamp)
for r in "${rows[@]:0:3}"; do
  test "$(grep "^$r/" <<<"$before")" = "$(grep "^$r/" <<<"$after")" || fail "$r was run again"
done
test "$(grep "^out/summary.csv " <<<"$before")" != "$(grep "^out/summary.csv " <<<"$after")" || fail "the summary was not made again"
test -s out/short/stick_head_turned_30/report.json || fail "the removed output was not made again"

# A job killed mid-way (voxmorph SIGKILLed while rendering the side view)
# leaves none of its row's outputs and no temporary files.
printf '#!/bin/sh\ncase "$*" in *azimuth=90*) kill -9 $$;; esac\nexec "%s" "$@"\n' "$bin" > killed_voxmorph.sh
chmod +x killed_voxmorph.sh
rm out/tall/stick_right_arm_out_30/front.png
if snakemake -s "$src/workflow/Snakefile" --cores 2 --config study=study.tsv voxmorph="$work/killed_voxmorph.sh" > run4.log 2>&1; then
  fail "the killed job did not fail the run"
fi
for f in "${files[@]}"; do test ! -e "out/tall/stick_right_arm_out_30/$f" || fail "the killed job left $f"; done
test ! -e out/tall/stick_right_arm_out_30/.partial || fail "the killed job left its temporary folder"
test "$(grep "^out/tall/stick_head_turned_30/" <<<"$before")" = "$(stamp | grep "^out/tall/stick_head_turned_30/")" \
  || fail "another row's outputs changed"

# A bad study file: an error naming the file, the line and the fault.
sed '3s/--preserve-volumes/--report x.json/' study.tsv > bad.tsv
if snakemake -s "$src/workflow/Snakefile" --cores 2 --config study=bad.tsv voxmorph="$bin" > bad.log 2>&1; then fail "bad study accepted"; fi
grep -q "bad.tsv:3: option '--report' is not one a study row may give" bad.log || { cat bad.log; fail "bad study message"; }
echo "study workflow: ok"
