#!/usr/bin/env bash
# The viewer turning joints, scripted on the AM phantom under Xvfb + lavapipe:
# opened with the arm joint pose, the same pose loaded and saved, the
# shoulder's abduction set as the Joints panel's slider sets it (60), then
# turned 15 degrees more by dragging the gizmo's abduction ring, the elbow
# flexed, saved, undone back to the loaded pose and saved again. Checks:
# the saved poses are joint poses with the expected angles (shoulder
# abduction 75 within the drag's precision, elbow flexion 30) and no other
# selection; the unchanged round trip saves what undo comes back to, and
# `voxmorph deform` gives it the same grid as the original file, byte for
# byte (the turned pose's deform is that of any joint pose, tested with the
# deform command). Bad input: an angle outside its
# joint's range in a script or in a pose is one line naming the joint, exit 1.
set -euo pipefail
bin=$1 src=$2 work=$3
grid="$src/assets/icrp110_am.nii.gz" organs="$src/assets/icrp110_am_organs.dat"
rm -rf "$work" && mkdir -p "$work"
cd "$work"
cp "$src/assets/poses/am_right_arm_raised_45_joints.json" joints.json

expect_one_line() {  # expected-message command...
  local expected=$1 out rc
  shift
  set +e
  out=$("$@" 2>&1)
  rc=$?
  set -e
  echo "$out"
  test "$rc" -eq 1 && test "$(echo "$out" | wc -l)" -eq 1 && echo "$out" | grep -qF "$expected"
}
echo '{"steps": [{"step": "set_joint", "joint": "right_shoulder", "dof": "abduction", "degrees": 200}]}' > bad_script.json
expect_one_line "bad_script.json: step 1: joint 'right_shoulder' abduction 200 is outside its range [-30, 180] degrees" \
  "$bin" view "$grid" --organs "$organs" --pose joints.json --script bad_script.json
echo '{"steps": [{"step": "set_joint", "joint": "right_elbow", "dof": "abduction", "degrees": 10}]}' > bad_dof.json
expect_one_line "bad_dof.json: step 1: joint 'right_elbow' has no 'abduction' (it has flexion)" \
  "$bin" view "$grid" --organs "$organs" --pose joints.json --script bad_dof.json
echo '{"joints": {"right_shoulder": {"abduction": 200}}}' > bad_pose.json
expect_one_line "bad_pose.json: joint 'right_shoulder' abduction 200 is outside its range [-30, 180] degrees" \
  "$bin" view "$grid" --organs "$organs" --pose bad_pose.json

xvfb-run -a -s "-screen 0 1280x800x24" "$bin" view "$grid" --organs "$organs" --pose joints.json \
  --script "$src/tests/app/data/viewer_joints_session.json" --screenshot-dir "$work" 2> >(tee session.log >&2)
test -s turned.png
cmp unchanged.json undone.json
python3 - <<'PY'
import json
unchanged, turned = json.load(open('unchanged.json')), json.load(open('turned.json'))
assert unchanged['joints'] == {'right_shoulder': {'abduction': 45}}, unchanged
assert unchanged['selections'] == [] and 'separations' not in unchanged, unchanged
assert set(turned['joints']) == {'right_shoulder', 'right_elbow'}, turned
assert set(turned['joints']['right_shoulder']) == {'abduction'}, turned
abduction = turned['joints']['right_shoulder']['abduction']
assert abs(abduction - 75) < 0.5, abduction
assert turned['joints']['right_elbow'] == {'flexion': 30}, turned
assert turned['selections'] == [] and 'separations' not in turned, turned
print(f'saved joints: shoulder abduction {abduction:.3f}, elbow flexion 30')
PY
for pose in joints unchanged; do
  "$bin" deform "$grid" --organs "$organs" --pose $pose.json -o $pose.nii.gz --preserve-volumes -q
done
cmp joints.nii.gz unchanged.nii.gz
echo "viewer joints session: passed"
