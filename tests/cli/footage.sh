#!/usr/bin/env bash
# Stylizing footage: coherent-noise driven by the flow node's motion and confidence,
# on the dolly shot's beauty pass alone (the frames of samples/footage/dolly), measured along the
# plate's true motion vectors with `nprfx measure`:
#   - warp correlation of the noise (alpha 0.98, the paper's) along the true motion >= 0.8 with
#     flow-derived motion, where the picture moves (over 0.5 px a frame: still pixels are alike
#     in every variant), far above the shower-door baseline (the same noise with no motion:
#     patterns stay on screen) and the white baseline (new noise every frame); the same noise
#     driven by the true motion is the ceiling, printed beside it;
#   - a cut in the middle of a sequence (dolly, then crossing): confidence collapses there and the
#     noise restarts (equals fresh noise, alpha 0) on nearly every pixel instead of smearing the
#     old shot's noise into the new one;
#   - the footage looks (samples/graphs/footage_*.json) render 3 frames of the sample footage.
# Skipped (77) in a build without an optical flow provider (no OpenCV).
#
# usage: bash footage.sh NPRFX_BINARY SOURCE_DIR WORK_DIR
set -u
NPRFX=$1; SRC=$2; W=$3
rm -rf "$W"; mkdir -p "$W"; cd "$W" || exit 1
SRC=$(cd "$SRC" && pwd)
passes=0; fails=0
pass() { passes=$((passes+1)); }
fail() { echo "FAIL: $*"; fails=$((fails+1)); }
ge() { awk -v a="$1" -v b="$2" 'BEGIN { exit !(a >= b) }'; }
lt() { awk -v a="$1" -v b="$2" 'BEGIN { exit !(a < b) }'; }

. "$SRC/tests/lib/flow.sh"
if flow_missing "$NPRFX"; then
  echo "footage: this build has no optical flow provider (OpenCV): skipped"
  exit 77
fi

# ---- coherence along the true motion -----------------------------------------------------------
# The plate has the true vectors for the measure; the flow sees only its Combined pass.
cat > cn.json <<EOF
{"frames": "1-12", "nodes": {
 "plate": {"node": "read", "path": "$SRC/samples/plates/dolly/dolly.####.exr", "vectors": "blender"},
 "flow": {"node": "flow", "inputs": {"image": "plate:Combined.RGB"}},
 "look": {"node": "coherent-noise", "inputs": {"motion_prev": "flow", "confidence": "flow"},
          "params": {"noise": "bandpass", "sigma_lo": 1, "sigma_hi": 4, "alpha": 0.98, "output": "unit01", "contrast": 0.25}},
 "w": {"node": "write", "inputs": {"image": "look"}, "path": "out/cn.####.exr"}
}}
EOF
# Shower door: the same noise driven by the plate's motion, which the variant zeroes.
sed 's/"motion_prev": "flow"/"motion_prev": "plate"/' cn.json > cn_plate.json
corr() { sed -n 's/^warp_corr //p'; }
m() { "$NPRFX" measure "$@" --node look --plate plate --threads 2 --moving 0.5; }
c_flow=$(m cn.json 2> m1.err | corr)
c_true=$(m cn_plate.json 2> m4.err | corr)
c_door=$(m cn_plate.json --variant shower-door 2> m2.err | corr)
c_white=$(m cn.json --variant white 2> m3.err | corr)
echo "warp correlation along the true motion, frames 1-12 of dolly, moving pixels: flow-driven $c_flow (true motion: $c_true), shower door $c_door, white $c_white"
[ -n "$c_flow" ] && ge "$c_flow" 0.8 && pass || fail "flow-driven noise: warp_corr '$c_flow' < 0.8: $(tail -c 300 m1.err)"
[ -n "$c_door" ] && lt "$c_door" 0.3 && pass || fail "shower door: warp_corr '$c_door' not < 0.3: $(cat m2.err)"
[ -n "$c_white" ] && lt "$c_white" 0.2 && pass || fail "white: warp_corr '$c_white' not < 0.2: $(cat m3.err)"

# ---- a cut: dolly 1-4, then crossing 5-8 ---------------------------------------------------------
mkdir -p cut
for f in 1 2 3 4; do cp "$SRC/samples/footage/dolly/dolly.000$f.png" cut/cut.000$f.png; done
for f in 5 6 7 8; do
  oiiotool "$SRC/samples/plates/crossing/crossing.000$f.exr" --ch "R=ViewLayer.Combined.R,G=ViewLayer.Combined.G,B=ViewLayer.Combined.B" \
    --colorconvert linear sRGB -d uint8 -o cut/cut.000$f.png >/dev/null 2>&1 || fail "oiiotool: crossing frame $f"
done
cat > cut.json <<'EOF'
{"frames": "1-8", "nodes": {
 "plate": {"node": "read", "path": "cut/cut.####.png", "colorspace": "srgb"},
 "flow": {"node": "flow", "inputs": {"image": "plate:R,G,B"}},
 "look": {"node": "coherent-noise", "inputs": {"motion_prev": "flow", "confidence": "flow"}, "params": {"alpha": 0.9}},
 "w": {"node": "write", "inputs": {"image": "look"}, "path": "out/n.####.exr"},
 "c": {"node": "write", "inputs": {"image": "flow:confidence.prev"}, "path": "out/c.####.exr"}
}}
EOF
"$NPRFX" run cut.json -q --output-dir carry 2> cut.err || fail "cut: $(cat cut.err)"
sed 's/"alpha": 0.9/"alpha": 0/' cut.json > fresh.json
"$NPRFX" run fresh.json -q --output-dir fresh --frames 5 2> fresh.err || fail "cut, fresh noise: $(cat fresh.err)"
# The share of frame 5's pixels that restarted (equal to alpha-0 noise), and frame 3's.
restarted() { "$NPRFX" diff "carry/out/n.000$1.exr" "fresh/out/n.000$1.exr" --fail 0 2>&1 | sed -n 's/.*pixels (\([0-9.]*\)%) over 0 (fail).*/\1/p' | head -1 | grep . || echo 0; }
"$NPRFX" run fresh.json -q --output-dir fresh --frames 3 2>/dev/null
d5=$(restarted 5); d3=$(restarted 3)
echo "cut at frame 5: $(awk -v d="$d5" 'BEGIN { print 100 - d }')% of pixels restarted there (frame 3: $(awk -v d="$d3" 'BEGIN { print 100 - d }')%)"
[ -n "$d5" ] && lt "$d5" 10 && pass || fail "cut: only $(awk -v d="$d5" 'BEGIN { print 100 - d }')% of frame 5 restarted (want > 90%)"
[ -n "$d3" ] && ge "$d3" 50 && pass || fail "no cut at frame 3, yet $(awk -v d="$d3" 'BEGIN { print 100 - d }')% restarted"

# ---- the footage looks ------------------------------------------------------------------------
for g in "$SRC"/samples/graphs/footage_*.json; do
  name=$(basename "$g" .json)
  "$NPRFX" run "$g" --frames 1-3 -q --output-dir "looks/$name" 2> "$name.err" && pass || fail "$name: $(cat "$name.err")"
done

echo "footage: $passes passed, $fails failed"
[ $fails -eq 0 ]
