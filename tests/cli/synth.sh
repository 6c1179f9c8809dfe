#!/bin/bash
# nprfx synth: writes one EXR per frame with every synth channel; usage errors exit 2.
# usage: synth.sh NPRFX SOURCE_DIR WORK_DIR
set -u
nprfx=$1
work=$3
rm -rf "$work" && mkdir -p "$work" || exit 1
fail() { echo "FAIL: $*" >&2; exit 1; }

out=$("$nprfx" synth orbit --frames 1-2 --size 64x64 -o "$work/o.####.exr" --threads 2) ||
    fail "synth orbit exited $?"
[ "$(printf '%s\n' "$out" | grep -c '^wrote ')" -eq 2 ] || fail "expected two 'wrote' lines: $out"
for f in 1 2; do
    [ -s "$work/o.000$f.exr" ] || fail "o.000$f.exr not written"
done

# Every channel is present at the requested size: oiiotool lists the full names; without it,
# nprfx info lists them grouped by layer.
if command -v oiiotool >/dev/null 2>&1; then
    info=$(oiiotool --info -v "$work/o.0002.exr") || fail "oiiotool --info exited $?"
    printf '%s\n' "$info" | grep -q '64 x *64, 26 channel' || fail "not 64x64 with 26 channels: $info"
    list=$(printf '%s\n' "$info" | grep 'channel list')
    for ch in R G B A Z motion_prev.X motion_prev.Y motion_next.X motion_next.Y P.X P.Y P.Z \
        Pref.X Pref.Y Pref.Z N.X N.Y N.Z UV.U UV.V id diffuse coverage albedo.R albedo.G albedo.B; do
        printf '%s\n' "$list" | grep -Eq "[ ,]$ch(,|$)" || fail "no channel $ch in $list"
    done
else
    info=$("$nprfx" info "$work/o.0002.exr") || fail "nprfx info exited $?"
    printf '%s\n' "$info" | grep -q '64x64' || fail "size is not 64x64: $info"
    for layer in 'motion_prev: X Y' 'motion_next: X Y' 'P: X Y Z' 'Pref: X Y Z' 'N: X Y Z' \
        'UV: U V'; do
        printf '%s\n' "$info" | grep -q "$layer" || fail "missing layer '$layer': $info"
    done
    for ch in R G B A Z id diffuse coverage; do
        printf '%s\n' "$info" | grep -Eq "(^| )$ch( |$)" || fail "missing channel $ch: $info"
    done
fi

# --layout blender: Blender's names and Vector convention. Read back with "vectors": "blender",
# the motion is the synth layout's exactly, and the beauty, albedo and depth are the same.
"$nprfx" synth orbit --frames 2 --size 48x32 --layout blender -o "$work/b.0002.exr" >/dev/null ||
    fail "--layout blender"
"$nprfx" synth orbit --frames 2 --size 48x32 -o "$work/s.0002.exr" >/dev/null || fail "synth 48x32"
cat >"$work/layout.json" <<EOF
{"frames": "2", "nodes": {
  "b": {"node": "read", "path": "b.####.exr", "vectors": "blender"},
  "s": {"node": "read", "path": "s.####.exr"},
  "wb": {"node": "write", "inputs": {"image": "b:motion_prev.X,motion_prev.Y,motion_next.X,motion_next.Y"}, "path": "mb.####.exr"},
  "ws": {"node": "write", "inputs": {"image": "s:motion_prev.X,motion_prev.Y,motion_next.X,motion_next.Y"}, "path": "ms.####.exr"},
  "b1": {"node": "write", "inputs": {"image": "b:Combined.RGB"}, "path": "b1.####.exr"},
  "s1": {"node": "write", "inputs": {"image": "s:R,G,B"}, "path": "s1.####.exr"},
  "b2": {"node": "write", "inputs": {"image": "b:DiffCol.RGB"}, "path": "b2.####.exr"},
  "s2": {"node": "write", "inputs": {"image": "s:albedo.R,albedo.G,albedo.B"}, "path": "s2.####.exr"},
  "b3": {"node": "write", "inputs": {"image": "b:Depth.Z"}, "path": "b3.####.exr"},
  "s3": {"node": "write", "inputs": {"image": "s:Z"}, "path": "s3.####.exr"},
  "b4": {"node": "write", "inputs": {"image": "b:IndexOB.X"}, "path": "b4.####.exr"},
  "s4": {"node": "write", "inputs": {"image": "s:id"}, "path": "s4.####.exr"}}}
EOF
"$nprfx" run "$work/layout.json" --quiet --output-dir "$work" || fail "reading the blender layout"
"$nprfx" diff "$work/mb.0002.exr" "$work/ms.0002.exr" --fail 0 --hardfail 0 >/dev/null ||
    fail "blender layout: the motion read back differs from the synth layout's"
for k in 1 2 3 4; do
    "$nprfx" diff "$work/b$k.0002.exr" "$work/s$k.0002.exr" --fail 0 --hardfail 0 >/dev/null ||
        fail "blender layout: Combined/DiffCol/Depth/IndexOB ($k) differ from R,G,B/albedo/Z/id"
done
"$nprfx" synth orbit --layout maya -o "$work/x.exr" 2>/dev/null
[ $? -eq 2 ] || fail "an unknown layout should exit 2"

# --half, --list and usage errors (each run costs a process start: keep them few).
"$nprfx" synth translate --size 32x16 --half -o "$work/t.exr" >/dev/null || fail "--half"
[ -s "$work/t.exr" ] || fail "t.exr not written"
"$nprfx" synth --list | grep -q '^ *dolly ' || fail "--list does not name dolly"
"$nprfx" synth nosuchscene -o "$work/x.exr" 2>/dev/null
[ $? -eq 2 ] || fail "unknown scene should exit 2"
"$nprfx" synth orbit --frames 1-2 -o "$work/x.exr" 2>/dev/null
[ $? -eq 2 ] || fail "several frames without a frame token should exit 2"
[ ! -e "$work/x.exr" ] || fail "a failed command wrote x.exr"
echo "synth.sh: ok"
