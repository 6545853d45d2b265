#!/usr/bin/env bash
# Scripted viewer session on the AM phantom under Xvfb + lavapipe: select the
# right arm, turn it 45 degrees with the gizmo, cut, slide the cut by its
# handle, undo back to rest, redo, save the pose, start an export and cancel
# it, export. Checks: the screenshots match the golden images (the ray
# caster's tolerance), the screenshot after undo equals the rest one and the
# one after redo the slid cut's, byte for byte; the cancelled export left
# nothing; `voxmorph deform --pose` on the saved pose writes a grid
# byte-identical to the export; the export's report records the grid's
# SHA-256 and the edited pose in its provenance.
set -euo pipefail
bin=$1 src=$2 work=$3
rm -rf "$work" && mkdir -p "$work"
cd "$work"
xvfb-run -a -s "-screen 0 1280x800x24" "$bin" view "$src/assets/icrp110_am.nii.gz" --organs "$src/assets/icrp110_am_organs.dat" \
  --pose "$src/assets/viewer/am_right_arm_free.json" --script "$src/tests/app/data/viewer_session.json" --screenshot-dir "$work" 2> >(tee session.log >&2)
grep -q "export cancelled; nothing written" session.log
# The export cancelled at once left nothing behind.
test ! -e cancelled.nii.gz && test ! -e cancelled.json
if ls -a | grep -q '^\.tmp-'; then echo "temporary files left behind"; ls -a; exit 1; fi
cmp rest.png undone.png
! cmp -s posed_cut.png posed_cut_slid.png  # the plane's handle moved the cut
cmp posed_cut_slid.png redone.png
"$bin" deform "$src/assets/icrp110_am.nii.gz" --organs "$src/assets/icrp110_am_organs.dat" --pose pose.json -o cli.nii.gz \
  --preserve-volumes -q
cmp cli.nii.gz export.nii.gz
test -s export.json && test -s export.png
# The export's report records its provenance: the grid's digest and the edited pose.
grep -q "\"sha256\": \"$(sha256sum "$src/assets/icrp110_am.nii.gz" | cut -c1-64)\"" export.json
grep -q '"path": "edited in the viewer' export.json
if [ -n "${VOX_UPDATE_GOLDEN:-}" ]; then  # regenerate, then look at the PNGs
  cp rest.png "$src/assets/golden/viewer_am_rest.png"
  cp posed.png "$src/assets/golden/viewer_am_right_arm_45.png"
  cp posed_cut.png "$src/assets/golden/viewer_am_right_arm_45_cut.png"
fi
python3 "$src/tests/app/golden_png.py" "$src/assets/golden" rest.png=viewer_am_rest.png posed.png=viewer_am_right_arm_45.png \
  posed_cut.png=viewer_am_right_arm_45_cut.png
echo "viewer session: passed"
