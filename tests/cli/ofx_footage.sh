#!/usr/bin/env bash
# Footage in an OpenFX Filter context: coherent-noise and advect applied to a plain
# footage clip, their motion and confidence computed inside the plug-in by the flow node on the
# Source clip (plugins/ofx/ofx_derive.c), on the 24 frames of samples/footage/dolly. The test host
# renders the General graph flow -> node with --footage: the node in the Filter context on the
# picture the flow node reads, so each result is compared with `nprfx run` of the same graph.
#  1. strict (temporal clip access: the plug-in fetches Source at t-1, t, t+1; tiles, 2 threads):
#     bit-identical to the runner, coherent-noise (motion_prev, motion_next and confidence
#     derived; also with noise = input, Source feeding the flow and the node) and advect; the
#     host checks on each first render that the Source frames fetched are exactly those that
#     getFramesNeeded declared.
#  2. mlt (Filter only, 8-bit, no temporal clip access, a new instance for every frame as melt
#     makes them: the plug-in keeps the previous Source frame and its flow, and an instance that
#     goes hands them to the next; the flow to the next frame cannot be had, so coherent-noise's
#     confidence is confidence.prev): rendered in order, equal to the runner within half an 8-bit
#     level (0.002): the output's rounding. The footage is 8-bit, so the host's 8-bit Source
#     loses nothing and the flow is the runner's. Two coherent-noise effects of different seeds
#     on the same footage each continue their own; two alike are refused, saying why.
#  3. mlt, out of order (frames 1-5, then 7-9): a jump is a cut: frames 7-9 equal (0.002) the
#     runner's render of a shot that starts at 7 (zero motion and confidence there, nodes
#     restart), and differ from the in-order result; never the flow against the wrong previous
#     frame. One frame skipped: frames 5 and 7 are alike enough that a flow between them would
#     pass the flow's own cut detection, so a plug-in that took 5 as 7's previous frame fails.
# Skipped (77) in a build without an optical flow provider (no OpenCV): the adapter then derives
# nothing (and coherent-noise and advect keep their clips).
#
# usage: NPRFX_OFXTEST=TEST_HOST_BINARY bash ofx_footage.sh NPRFX_BINARY SOURCE_DIR WORK_DIR
set -u
NPRFX=$1; SRC=$2; W=$3
OFXTEST=${NPRFX_OFXTEST:-}
BUNDLE=${NPRFX_OFX_BUNDLE:-$(cd "$(dirname "$NPRFX")" && pwd)/plugins/ofx/nprfx.ofx.bundle}
rm -rf "$W"; mkdir -p "$W"
W=$(cd "$W" && pwd); SRC=$(cd "$SRC" && pwd)
passes=0; fails=0
pass() { passes=$((passes+1)); }
fail() { echo "FAIL: $*"; fails=$((fails+1)); }

. "$SRC/tests/lib/flow.sh"
if flow_missing "$NPRFX"; then
  echo "ofx_footage: this build has no optical flow provider (OpenCV): skipped"
  exit 77
fi
if [ -z "$OFXTEST" ] || [ ! -x "$OFXTEST" ]; then
  echo "FAIL: no test host: NPRFX_OFXTEST='$OFXTEST' is not an executable nprfx-ofxtest"
  exit 1
fi
if [ ! -d "$BUNDLE" ]; then echo "FAIL: no bundle $BUNDLE"; exit 1; fi
ofx() { "$OFXTEST" run "$@" --ofx "$BUNDLE" --footage --quiet; }
# diff GRAPH_OUT_A GRAPH_OUT_B TOLERANCE: every frame of the sequence within the tolerance
within() { "$NPRFX" diff "$1" "$2" --fail "$3" --warn "$3" > "$W/diff.log" 2>&1; }

# The footage is read as stored (no colour conversion): 8-bit values k/255, which an 8-bit host
# gives back exactly, so under mlt only the output's quantisation differs.
graph() { # NAME INPUTS PARAMS OUT > graph
  cat <<G
{"frames": "1-24", "nodes": {
 "plate": {"node": "read", "path": "$SRC/samples/footage/dolly/dolly.####.png"},
 "flow": {"node": "flow", "inputs": {"image": "plate:R,G,B"}},
 "n": {"node": "$1", "inputs": {$2}, "params": {$3}},
 "w": {"node": "write", "inputs": {"image": "n"}, "path": "$4.####.exr"}}}
G
}
# unit01 with a small contrast keeps the noise inside [0, 1] (10 sigma), where 8 bits hold it
graph coherent-noise '"motion_prev": "flow", "motion_next": "flow", "confidence": "flow"' \
  '"alpha": 0.9, "output": "unit01", "contrast": 0.05' cn > "$W/cn.json"
graph coherent-noise '"motion_prev": "flow", "confidence": "flow:confidence.prev"' \
  '"alpha": 0.9, "output": "unit01", "contrast": 0.05' cn > "$W/cn_mlt.json"
graph coherent-noise '"motion_prev": "flow", "confidence": "flow", "source": "plate:R,G,B"' \
  '"noise": "input", "alpha": 0.8' cni > "$W/cn_input.json"
graph advect '"motion_prev": "flow", "confidence": "flow"' '"output": "layers", "period": 8' \
  uv > "$W/advect.json"

# GRAPH DIR TOL OFX_OPTIONS...: GRAPH rendered by nprfx run and through the test host into DIR,
# the same within TOL.
against_run() {
  local g=$1 dir=$2 tol=$3; shift 3
  "$NPRFX" run "$W/$g.json" --output-dir "$W/$g/direct" --quiet 2> "$W/$g.direct.log" ||
    { fail "$g: direct render: $(tail -n 2 "$W/$g.direct.log")"; return; }
  local out; out=$(cd "$W/$g/direct" && ls *.exr | head -n 1); out=${out%%.*}
  if ! ofx "$W/$g.json" --output-dir "$W/$g/$dir" "$@" 2> "$W/$g.$dir.log"; then
    fail "$g under $dir: $(tail -n 2 "$W/$g.$dir.log" | tr '\n' ' ')"; return
  fi
  if within "$W/$g/direct/$out.####.exr" "$W/$g/$dir/$out.####.exr" "$tol"; then pass
  else fail "$g under $dir differs from nprfx run by more than $tol:"; tail -n 5 "$W/diff.log"; fi
}

# --- 1. strict: bit-identical -------------------------------------------------------------------
for g in cn cn_input advect; do against_run $g strict 0 --tile 37 --threads 2; done

# --- 2. mlt, in order: within the output's rounding ----------------------------------------------
for g in cn_mlt advect; do against_run $g mlt 0.002 --profile mlt; done

# two effects on the footage, each with its own instances: told apart by their params
cat > "$W/cn_two.json" <<G
{"frames": "1-6", "nodes": {
 "plate": {"node": "read", "path": "$SRC/samples/footage/dolly/dolly.####.png"},
 "flow": {"node": "flow", "inputs": {"image": "plate:R,G,B"}},
 "a": {"node": "coherent-noise", "inputs": {"motion_prev": "flow", "confidence": "flow:confidence.prev"},
       "params": {"alpha": 0.9, "output": "unit01", "contrast": 0.05, "seed": 1}},
 "b": {"node": "coherent-noise", "inputs": {"motion_prev": "flow", "confidence": "flow:confidence.prev"},
       "params": {"alpha": 0.9, "output": "unit01", "contrast": 0.05, "seed": SEED}},
 "wa": {"node": "write", "inputs": {"image": "a"}, "path": "two_a.####.exr"},
 "wb": {"node": "write", "inputs": {"image": "b"}, "path": "two_b.####.exr"}}}
G
sed -i 's/SEED/2/' "$W/cn_two.json"
against_run cn_two mlt 0.002 --profile mlt
if within "$W/cn_two/direct/two_b.####.exr" "$W/cn_two/mlt/two_b.####.exr" 0.002; then pass
else fail "cn_two under mlt: the second effect differs from nprfx run:"; tail -n 5 "$W/diff.log"; fi
# two alike effects (same params) on footage of one size but other pixels (the dolly footage and
# the crossing shot's beauty): the frame after cannot tell whose it is, so it is refused
cat > "$W/cn_alike.json" <<G
{"frames": "1-6", "nodes": {
 "plate": {"node": "read", "path": "$SRC/samples/footage/dolly/dolly.####.png"},
 "plate2": {"node": "read", "path": "$SRC/samples/plates/crossing/crossing.####.exr"},
 "flow": {"node": "flow", "inputs": {"image": "plate:R,G,B"}},
 "flow2": {"node": "flow", "inputs": {"image": "plate2:beauty.RGB"}},
 "a": {"node": "coherent-noise", "inputs": {"motion_prev": "flow", "confidence": "flow:confidence.prev"},
       "params": {"alpha": 0.9, "output": "unit01", "contrast": 0.05, "seed": 1}},
 "b": {"node": "coherent-noise", "inputs": {"motion_prev": "flow2", "confidence": "flow2:confidence.prev"},
       "params": {"alpha": 0.9, "output": "unit01", "contrast": 0.05, "seed": 1}},
 "wa": {"node": "write", "inputs": {"image": "a"}, "path": "alike_a.####.exr"},
 "wb": {"node": "write", "inputs": {"image": "b"}, "path": "alike_b.####.exr"}}}
G
if ofx "$W/cn_alike.json" --output-dir "$W/alike" --profile mlt 2> "$W/alike.log"; then
  fail "two alike effects on other footage under mlt rendered: one may have continued the other's frames"
elif grep -q "cannot tell which" "$W/alike.log"; then pass
else fail "two alike effects under mlt: refused without the reason: $(tail -n 2 "$W/alike.log" | tr '\n' ' ')"; fi

# --- 3. mlt, out of order: a jump restarts --------------------------------------------------------
for g in cn_mlt advect; do
  out=$([ $g = advect ] && echo uv || echo cn)
  if ! ofx "$W/$g.json" --profile mlt --output-dir "$W/$g/jump" --frames 1-5,7-9 \
       2> "$W/$g.jump.log"; then
    fail "$g under mlt, frames 1-5,7-9: $(tail -n 2 "$W/$g.jump.log" | tr '\n' ' ')"; continue
  fi
  "$NPRFX" run "$W/$g.json" --output-dir "$W/$g/cut" --shot 7-24 --frames 7-9 --quiet
  for f in 0007 0008 0009; do
    if within "$W/$g/cut/$out.$f.exr" "$W/$g/jump/$out.$f.exr" 0.002; then pass
    else fail "$g under mlt: frame $f after a jump is not the restart (a shot from 7):"; tail -n 3 "$W/diff.log"; fi
  done
  # and the restart is visible: frame 7 of the shot from 1 is another picture
  if within "$W/$g/direct/$out.0007.exr" "$W/$g/jump/$out.0007.exr" 0.002; then
    fail "$g under mlt: frame 7 after a jump equals the in-order render (the test cannot see a restart)"
  else pass; fi
  for f in 0001 0005; do
    if within "$W/$g/direct/$out.$f.exr" "$W/$g/jump/$out.$f.exr" 0.002; then pass
    else fail "$g under mlt: frame $f (in order before the jump) differs from nprfx run"; fi
  done
done

echo "$passes passed, $fails failed"
[ $fails -eq 0 ] && [ $passes -gt 0 ]
