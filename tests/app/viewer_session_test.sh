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
python3 - "$src/assets/golden" <<'PY'
import sys, zlib, struct
def load(path):
    d = open(path, 'rb').read()
    w, h, depth, ctype = struct.unpack('>IIBB', d[16:26])
    assert depth == 8 and ctype == 2, path
    i, idat = 8, b''
    while i < len(d):
        n = struct.unpack('>I', d[i:i + 4])[0]
        if d[i + 4:i + 8] == b'IDAT': idat += d[i + 8:i + 8 + n]
        i += 12 + n
    raw, rows, prev, stride = zlib.decompress(idat), [], bytearray(w * 3), w * 3
    for y in range(h):
        f, line = raw[y * (stride + 1)], bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for x in range(stride):
            a = line[x - 3] if x >= 3 else 0
            b = prev[x]
            c = prev[x - 3] if x >= 3 else 0
            if f == 1: line[x] = (line[x] + a) & 255
            elif f == 2: line[x] = (line[x] + b) & 255
            elif f == 3: line[x] = (line[x] + (a + b) // 2) & 255
            elif f == 4:
                p = a + b - c; pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                line[x] = (line[x] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        rows.append(line); prev = line
    return w, h, rows
golden = sys.argv[1]
for shot, gold in [('rest.png', 'viewer_am_rest.png'), ('posed.png', 'viewer_am_right_arm_45.png'),
                   ('posed_cut.png', 'viewer_am_right_arm_45_cut.png')]:
    w, h, a = load(shot)
    gw, gh, b = load(golden + '/' + gold)
    assert (w, h) == (gw, gh), (shot, w, h, gw, gh)
    differing = sum(1 for y in range(h) for x in range(w)
                    if max(abs(a[y][3 * x + k] - b[y][3 * x + k]) for k in range(3)) > 5)
    print(f'{shot}: {differing} of {w * h} pixels differ from {gold} by more than 5/255')
    assert differing <= 0.001 * w * h, shot
PY
echo "viewer session: passed"
