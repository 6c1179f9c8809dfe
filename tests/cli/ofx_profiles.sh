#!/usr/bin/env bash
# The OpenFX adapter in the hosts the test host imitates (`nprfx-ofxtest run --profile
# NAME`, tests/ofxhost/profile.c):
#  1. strict and natron (General context always, message formatting that drops the arguments):
#     every test graph renders bit-identically to `nprfx run`. tests/graphs/ uses every node, and
#     every render also checks that each instance's first render fetches exactly the frames
#     getFramesNeeded declared.
#  2. strict, natron and mlt: a render-time error of a node (tone's percentiles the wrong way
#     round) reaches the runner's error in the node's own words, and under mlt (no temporal clip
#     access) a tone measuring another frame, or the shot, fails with words that say which frame
#     or why.
#  3. mlt and mlt16 (Filter context only, 8- or 16-bit images, no temporal clip access): every
#     plug-in either renders a one-node graph on its Source clip or is reported unavailable with
#     a reason; time-offset is refused for the missing temporal access, and so are coherent-noise
#     and advect in a build without optical flow (with it they take footage as Source and derive
#     their motion: tests/cli/ofx_footage.sh); tone with range manual matches the direct render
#     within the quantisation.
#  4. strict and natron: stipple with 'coverage' (5 channels) renders R, G, B as the runner does
#     and the coverage in A (the test host reads A back as the coverage channel), and its
#     'export' files (CSV and SVG, absolute paths) are written by the plug-in byte-identical to
#     the runner's.
#  5. natron: coherent-noise rendered in order declares, after its first frame, only what its
#     state still needs (depth at t-1 and t, the motion at t), not the recursion from the shot's
#     start, and renders the runner's pixels (the host refuses any fetch outside what was
#     declared).
# Against an adapter that declares frames it does not read, or that lacks message suite 2, 8/16-
# bit images, refusals at load, 5-channel output or exports, parts fail: that is what they test.
#
# usage: NPRFX_OFXTEST=TEST_HOST_BINARY bash ofx_profiles.sh NPRFX_BINARY SOURCE_DIR WORK_DIR
# (ctest sets NPRFX_OFXTEST to the nprfx-ofxtest it built; NPRFX_OFX_BUNDLE overrides the bundle,
# e.g. to try an adapter built elsewhere)
set -u
NPRFX=$1; SRC=$2; W=$3
OFXTEST=${NPRFX_OFXTEST:-}
BUNDLE=${NPRFX_OFX_BUNDLE:-$(cd "$(dirname "$NPRFX")" && pwd)/plugins/ofx/nprfx.ofx.bundle}
rm -rf "$W"; mkdir -p "$W"
W=$(cd "$W" && pwd) # absolute: export paths are given to the plug-in as they are
passes=0; fails=0
pass() { passes=$((passes+1)); }
fail() { echo "FAIL: $*"; fails=$((fails+1)); }

if [ -z "$OFXTEST" ] || [ ! -x "$OFXTEST" ]; then
  echo "FAIL: no test host: NPRFX_OFXTEST='$OFXTEST' is not an executable nprfx-ofxtest"
  exit 1
fi
if [ ! -d "$BUNDLE" ]; then echo "FAIL: no bundle $BUNDLE"; exit 1; fi

ofx() { "$OFXTEST" run "$@" --ofx "$BUNDLE"; }
same() { "$NPRFX" diff "$1" "$2" --fail 0 --hardfail 0 --warn 0 "${@:3}" > /dev/null 2>&1; }

# --- 1. every test graph under strict and natron, bit-identical ------------------------------
. "$SRC/tests/lib/flow.sh"
for g in "$SRC"/tests/graphs/*.json; do
  needs_missing_flow "$NPRFX" "$g" && continue # no optical flow in this build
  name=$(basename "$g" .json)
  if ! "$NPRFX" run "$g" --output-dir "$W/graphs/$name/direct" --quiet; then
    fail "$g: direct render"; continue
  fi
  files=$(cd "$W/graphs/$name/direct" && find . -name '*.exr' | sort)
  for profile in strict natron; do
    out="$W/graphs/$name/$profile"
    if ! ofx "$g" --profile "$profile" --output-dir "$out" --quiet --tile 37 --threads 2 \
         2> "$out.log"; then
      fail "$g under $profile: $(tail -n 2 "$out.log" | tr '\n' ' ')"; continue
    fi
    bad=0
    for f in $files; do
      same "$W/graphs/$name/direct/$f" "$out/$f" || { bad=1; fail "$g under $profile: $f differs"; }
    done
    [ $bad -eq 0 ] && pass
  done
done

# --- 2. render-time errors arrive in the node's words ----------------------------------------
mkdir -p "$W/error"
cat > "$W/error.json" <<'G'
{"frames": "1-2", "nodes": {"plate": {"node": "synth", "scene": "dolly", "size": "32x24"},
 "t": {"node": "tone", "inputs": {"tone": "plate:diffuse"},
       "params": {"range": "frame", "reference_frame": 1, "low": 60, "high": 40}},
 "w": {"node": "write", "inputs": {"image": "t"}, "path": "t.####.exr"}}}
G
if "$NPRFX" run "$W/error.json" --output-dir "$W/error/direct" --frames 1 > "$W/error/direct.log" 2>&1 ||
   ! grep -q "must be below high" "$W/error/direct.log"; then
  fail "the direct render of error.json did not fail with 'must be below high' (the test needs a new provocation)"
fi
for profile in strict natron mlt; do
  log="$W/error/$profile.log"
  if ofx "$W/error.json" --profile "$profile" --output-dir "$W/error/$profile" --frames 1 > "$log" 2>&1; then
    fail "$profile: tone with low > high rendered"
  elif grep -q "the plug-in's error message is empty" "$log"; then
    fail "$profile: the plug-in's error message is empty: $(grep 'failed' "$log" | head -n 1)"
  elif grep -q "percentile low (60) must be below high (40)" "$log"; then pass
  else fail "$profile: the error does not carry the node's words: $(grep 'failed' "$log" | head -n 1)"
  fi
done
# mlt cannot fetch other frames: measuring frame 2 while rendering frame 1 fails, saying so.
log="$W/error/mlt_frame.log"
if ofx "$W/error.json" --profile mlt --output-dir "$W/error/mlt_frame" --frames 1 \
     --set t.reference_frame=2 --set t.low=1 --set t.high=99 > "$log" 2>&1; then
  fail "mlt: tone measuring frame 2 rendered frame 1 without temporal clip access"
elif grep -q "the plug-in's error message is empty" "$log"; then
  fail "mlt: the plug-in's error message is empty: $(grep 'failed' "$log" | head -n 1)"
elif grep -q "org.nprfx.Tone.*frame 2" "$log"; then pass
else fail "mlt: the error does not name frame 2: $(grep 'failed' "$log" | head -n 1)"
fi
# Nor can it give the shot: tone's default range (the shot), even over a one-frame shot as this
# host reports it, fails saying why, instead of measuring each frame on its own.
sed 's/"frames": "1-2"/"frames": "1"/' "$W/error.json" > "$W/one_frame.json"
log="$W/error/mlt_shot.log"
if ofx "$W/one_frame.json" --profile mlt --output-dir "$W/error/mlt_shot" \
     --set t.range=shot --set t.low=1 --set t.high=99 > "$log" 2>&1; then
  fail "mlt: tone with range 'shot' rendered a frame measured on its own"
elif grep -q "org.nprfx.Tone.*which frames make it is not known here" "$log"; then pass
else fail "mlt: tone's range 'shot' fails without its reason: $(grep 'failed' "$log" | head -n 1)"
fi

# --- 3. mlt and mlt16: every plug-in renders through Filter or is unavailable with a reason ---
# A node's inputs from its help: "  name  N channels, required|optional ...".
inputs_of() {
  "$NPRFX" help "$1" | sed -n '/^Inputs:/,/^Params:/p' | awk '/^  [a-z_]+ +[0-9]/ {print $1, ($0 ~ /required/ ? "required" : "optional")}'
}
# The channels of the synthetic plate an input reads: by its name where the plate has that AOV,
# else any of the right count (the data only has to be plausible: the test is whether it runs).
channels_for() { # NODE INPUT
  case "$2" in
    depth) echo Z; return ;; id) echo id; return ;; alpha|coverage) echo coverage; return ;;
    motion_prev|motion_next) echo "$2.X,$2.Y"; return ;; normal) echo N.X,N.Y,N.Z; return ;;
  esac
  case $("$NPRFX" help "$1" | awk -v i="$2" '$1 == i {print $2; exit}') in
    1) echo diffuse ;; 2) echo UV.U,UV.V ;; 3) echo R,G,B ;; *) echo R,G,B,A ;;
  esac
}
# The one-node graph: the named inputs read the synthetic plate.
one_node() { # NODE INPUT... > graph
  local node=$1 ins="" i; shift
  for i in "$@"; do ins="$ins${ins:+, }\"$i\": \"plate:$(channels_for "$node" "$i")\""; done
  printf '{"frames": "1-2", "nodes": {"plate": {"node": "synth", "scene": "orbit", "size": "32x24"},\n'
  # tone measures the whole shot by default, which a host without temporal access cannot give
  local params='{}'; [ "$node" = tone ] && params='{"range": "manual"}'
  printf ' "n": {"node": "%s", "inputs": {%s}, "params": %s},\n' "$node" "$ins" "$params"
  printf ' "w": {"node": "write", "inputs": {"image": "n"}, "path": "n.####.exr"}}}\n'
}
nodes=$("$NPRFX" list | awk '$2 != "I/O" {print $1}')
# The footage nodes: with optical flow their Filter context's Source is footage (ofx_footage.sh)
footage_nodes="coherent-noise advect"
flow_missing "$NPRFX" && footage_nodes=""
mkdir -p "$W/mlt"
for profile in mlt mlt16; do
  for node in $nodes; do
    case " $footage_nodes " in *" $node "*)
      echo "$profile $node: footage, tests/cli/ofx_footage.sh" >> "$W/mlt/$profile.txt"; continue ;;
    esac
    d="$W/mlt/$profile/$node"; mkdir -p "$d"
    required=$(inputs_of "$node" | awk '$2 == "required" {print $1}' | tr '\n' ' ')
    # with required inputs, those (Filter has one clip: a plug-in with two is unavailable);
    # else each input in turn, until the one that is the Source clip
    if [ -n "$required" ]; then tries=("$required"); else mapfile -t tries < <(inputs_of "$node" | awk '{print $1}'); fi
    verdict=""
    for t in "${tries[@]}"; do
      # shellcheck disable=SC2086
      one_node "$node" $t > "$d/graph.json"
      if ofx "$d/graph.json" --profile "$profile" --output-dir "$d/out" > "$d/log" 2>&1; then
        if [ -f "$d/out/n.0001.exr" ]; then verdict=renders; else verdict="rendered no EXR"; fi
        break
      fi
      if grep -q "has only the Filter context" "$d/log"; then continue; fi
      # the node's error, not the list of unavailable plug-ins printed at load ("ofx: ...")
      reason=$(grep -v '^ofx: ' "$d/log" | sed -n 's/.* is not available in this host: \(.*\)$/\1/p' | tail -n 1)
      if [ -n "$reason" ]; then verdict="unavailable: $reason"; else verdict="failed: $(grep -v '^ofx: ' "$d/log" | head -n 2 | tr '\n' ' ')"; fi
      break
    done
    echo "$profile $node: ${verdict:-no input is its Source clip}" >> "$W/mlt/$profile.txt"
    case "$verdict" in
      renders|unavailable:?*) pass ;;
      *) fail "$profile: $node neither renders through the Filter context nor is unavailable with a reason (${verdict:-no input is its Source clip})" ;;
    esac
    case "$node" in
      time-offset|coherent-noise|advect)
        if echo "$verdict" | grep -qi "temporal"; then pass
        else fail "$profile: $node is not refused for the missing temporal clip access ($verdict)"; fi ;;
    esac
  done
  # tone, range manual: within the quantisation of the host's images (input and output each
  # rounded to the nearest level, the manual range's slope 1)
  [ "$profile" = mlt ] && tol=0.00393 || tol=0.0000155
  cat > "$W/mlt/tone.json" <<'G'
{"frames": "1-2", "nodes": {"plate": {"node": "synth", "scene": "orbit", "size": "32x24"},
 "t": {"node": "tone", "inputs": {"tone": "plate:diffuse"}, "params": {"range": "manual"}},
 "w": {"node": "write", "inputs": {"image": "t"}, "path": "t.####.exr"}}}
G
  "$NPRFX" run "$W/mlt/tone.json" --output-dir "$W/mlt/tone_direct" --quiet
  if ! ofx "$W/mlt/tone.json" --profile "$profile" --output-dir "$W/mlt/tone_$profile" --quiet \
       > "$W/mlt/tone_$profile.log" 2>&1; then
    fail "$profile: tone (range manual) did not render: $(tail -n 1 "$W/mlt/tone_$profile.log")"
  elif "$NPRFX" diff "$W/mlt/tone_direct/t.####.exr" "$W/mlt/tone_$profile/t.####.exr" \
         --fail "$tol" --warn "$tol" > "$W/mlt/tone_$profile.diff" 2>&1; then pass
  else fail "$profile: tone (range manual) differs from the direct render by more than $tol:"
       cat "$W/mlt/tone_$profile.diff"
  fi
done

# --- 4. stipple: coverage in A, exports written by the plug-in --------------------------------
stipple_graph() { # EXPORT_DIR > graph
  cat <<G
{"frames": "1-2", "nodes": {"plate": {"node": "synth", "scene": "orbit", "size": "64x48"},
 "dots": {"node": "stipple", "inputs": {"tone": "plate:diffuse", "uv": "plate:UV.U,UV.V", "id": "plate:id"},
          "params": {"size": 3, "tile": 6, "coverage": true, "export": "$1/dots.####.csv"}},
 "svg": {"node": "stipple", "inputs": {"tone": "plate:diffuse"},
         "params": {"size": 2, "export": "$1/flat.####.svg"}},
 "w1": {"node": "write", "inputs": {"image": "dots"}, "path": "dots.####.exr"},
 "w2": {"node": "write", "inputs": {"image": "svg"}, "path": "flat.####.exr"}}}
G
}
S="$W/stipple"; mkdir -p "$S"
stipple_graph "$S/direct_export" > "$S/direct.json"
if ! "$NPRFX" run "$S/direct.json" --output-dir "$S/direct" --quiet; then fail "stipple: direct render"; fi
for profile in strict natron; do
  stipple_graph "$S/${profile}_export" > "$S/$profile.json"
  if ! ofx "$S/$profile.json" --profile "$profile" --output-dir "$S/$profile" --quiet \
       --tile 37 --threads 2 > "$S/$profile.log" 2>&1; then
    fail "stipple under $profile: $(tail -n 2 "$S/$profile.log" | tr '\n' ' ')"; continue
  fi
  for f in 0001 0002; do
    if same "$S/direct/dots.$f.exr" "$S/$profile/dots.$f.exr" --channels R,G,B,coverage; then pass
    else fail "stipple under $profile: frame $f: R,G,B or coverage (from A) differ from the runner's"; fi
    same "$S/direct/flat.$f.exr" "$S/$profile/flat.$f.exr" && pass || fail "stipple under $profile: flat.$f.exr differs"
    for e in dots.$f.csv flat.$f.svg; do
      if [ ! -f "$S/${profile}_export/$e" ]; then fail "stipple under $profile: the plug-in wrote no $e"
      elif cmp -s "$S/direct_export/$e" "$S/${profile}_export/$e"; then pass
      else fail "stipple under $profile: $e differs from the runner's"; fi
    done
  done
done

# --- 5. coherent-noise in order: the host prepares the new frame, not the whole past ----------
C=$W/cn_order
mkdir -p "$C"
cat > "$C/cn.json" <<G
{"frames": "1-24", "nodes": {
 "plate": {"node": "synth", "scene": "orbit", "size": "64x48"},
 "noise": {"node": "coherent-noise", "inputs": {"depth": "plate", "motion_prev": "plate"}, "params": {"seed": 4}},
 "w": {"node": "write", "inputs": {"image": "noise"}, "path": "noise.####.exr"}}}
G
"$NPRFX" run "$C/cn.json" --output-dir "$C/direct" --quiet || fail "coherent-noise: direct render"
if NPRFX_OFXTEST_FRAMES_LOG=$C/frames.log ofx "$C/cn.json" --profile natron --output-dir "$C/natron" \
     --quiet --threads 2 2> "$C/natron.log"; then
  bad=0
  for f in $(seq -f %04g 1 24); do same "$C/direct/noise.$f.exr" "$C/natron/noise.$f.exr" || bad=1; done
  [ $bad -eq 0 ] && pass || fail "coherent-noise under natron in order differs from the runner"
  # every declaration after frame 1: at most 2 frames a clip (and frame 1 declared 1 frame)
  wide=$(awk 'tolower($1) ~ /coherent/ && $3 >= 2 && $5 - $4 > 1' "$C/frames.log" | head -n 3)
  total=$(awk 'tolower($1) ~ /coherent/ { n += $5 - $4 + 1 } END { print n + 0 }' "$C/frames.log")
  if [ -z "$wide" ] && [ "$total" -gt 0 ] && [ "$total" -le $((24 * 2 * 2)) ]; then pass
  else fail "coherent-noise in order declared more than its state needs (clip-frames declared: $total; e.g. $wide)"; fi
else
  fail "coherent-noise under natron: $(tail -n 2 "$C/natron.log" | tr '\n' ' ')"
fi

echo "$passes passed, $fails failed"
[ $fails -eq 0 ] && [ $passes -gt 0 ]
