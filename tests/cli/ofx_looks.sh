#!/usr/bin/env bash
# The look plug-ins (plugins/ofx/ofx_look.c): each graph file of a looks folder is one effect that
# evaluates the graph inside the plug-in, its plates served from the host's clips (Source the
# picture, one clip per AOV). `nprfx-ofxtest look GRAPH` drives a look as a host does, its clips
# fed with the graph's own plates' AOVs in nprfx's conventions, and every render checks that the
# first render fetches exactly the frames getFramesNeeded declared.
#  1. every look the bundle ships (the sample graphs that name their knobs) renders frames 1-3 of
#     a 4-frame shot bit-identically to `nprfx run` of its graph, from separate clips (strict: one
#     clip per AOV, fed in nprfx's conventions) and from one multilayer Source (natron: a
#     multi-plane host whose Source carries every layer of the plate file, which the look reads
#     under the renderer's own names), each in order and frame by frame out of order (1, 3, 2),
#     strict's out of order as a proxy (render scale 0.5: the plates are the half-size images of
#     a project twice their size, motion in the project's pixels as hosts carry it, and the look
#     draws as the runner does on those plates at the graph's design width).
#  2. natron: toon and watercolor over 1-6 of an 8-frame shot in order, and toon frame by frame
#     out of order (odd frames, then even), bit-identical; strict: toon out of order.
#  3. knobs: toon with two knobs turned (ink.width, bands.bands) equals `nprfx run --set` of the
#     same, and differs from the look at its defaults.
#  4. frames declared: rendered in order, after its first frames toon declares its clips at t-1
#     and t only (tone's range kept from the first frame, coherent-noise stepping on), not the
#     shot.
#  5. mlt (no temporal clip access): the looks are unavailable, with the reason. strict8 (8-bit
#     images, temporal access): a look with a data AOV clip (depth, ...) is unavailable, naming
#     the clip; the footage looks (Source only) render, within the host's 8-bit steps of the
#     runner (mean error at most 0.01).
#  6. Analyze Shot (toon measures its light over the shot): pressed before the first render, the
#     render of frame 3 declares what coherent-noise's recursion reads (1-3), not the shot, and
#     frames 3-5 equal the runner's.
#  7. natron, which layer feeds an AOV: Find AOV Layers shows them (depth = ViewLayer.Depth.Z);
#     on plates whose depth layer is renamed (ViewLayer.Zdepth.Z) toon fails as the runner does,
#     naming the input, and with AOV Layers "depth = ViewLayer.Zdepth.Z" equals the runner
#     reading them with the same mapping (a read's "aovs" file); the layer menus show the layer
#     feeding each AOV after Find AOV Layers, and choosing ViewLayer.Zdepth.Z in the Depth layer
#     menu equals that mapping; Find on those plates, depth not found, still fails naming it.
#     On every renderer layout of `nprfx synth` (bare channels put on the planes Nuke uses) toon
#     from one Source equals the runner, and the menus show the channels each profile reads.
#  8. the look's version (the minor hosts key cached frames on) changes when its graph file does.
#  9. two writers at once (natron): main.json's look project is one look node per write node on
#     one Read; both nodes, each an instance of its own, render frames 1-4 in order on two
#     threads at the same time, as a host renders two writers, and each equals its write node's
#     frames from the runner.
#
# usage: NPRFX_OFXTEST=TEST_HOST_BINARY bash ofx_looks.sh NPRFX_BINARY SOURCE_DIR WORK_DIR
set -u
NPRFX=$1; SRC=$2; W=$3
OFXTEST=${NPRFX_OFXTEST:-}
BUNDLE=${NPRFX_OFX_BUNDLE:-$(cd "$(dirname "$NPRFX")" && pwd)/plugins/ofx/nprfx.ofx.bundle}
rm -rf "$W"; mkdir -p "$W"
W=$(cd "$W" && pwd); SRC=$(cd "$SRC" && pwd)
passes=0; fails=0
pass() { passes=$((passes+1)); }
fail() { echo "FAIL: $*"; fails=$((fails+1)); }
if [ -z "$OFXTEST" ] || [ ! -x "$OFXTEST" ]; then
  echo "FAIL: NPRFX_OFXTEST is not set to the test host (ctest sets it)"; exit 1; fi

# the runner's output of GRAPH's first write node over FRAMES into DIR; prints its pattern
runner() { # GRAPH FRAMES DIR [--set ...]
  local g=$1 f=$2 d=$3; shift 3
  "$NPRFX" run "$g" --frames "$f" --output-dir "$d" --quiet --threads 2 "$@" >/dev/null 2>"$d.log" || return 1
  python3 -c "import json,sys;g=json.load(open(sys.argv[1]));print([v['path'] for v in g['nodes'].values() if v.get('node')=='write'][0])" "$g"
}
# compare the runner's frames with the look's (STEM.####.exr in LOOKDIR)
same_frames() { # RUNNER_PATTERN LOOKDIR STEM FRAMES... (one diff of the two sequences)
  local pat=$1 dir=$2 stem=$3; shift 3
  local list; list=$(IFS=,; echo "$*")
  "$NPRFX" diff "$pat" "$dir/$stem.####.exr" --frames "$list" --fail 0 --hardfail 0 --warn 0 -q >/dev/null 2>&1
}
channels_of() { "$NPRFX" info "$1" | sed -n 3p | sed 's/ (.*//; s/^ *//; s/ /,/g'; }

look() { # PROFILE GRAPH FRAMES OUTDIR [options]
  local pf=$1 g=$2 f=$3 d=$4; shift 4
  mkdir -p "$d"
  "$OFXTEST" look "$g" --ofx "$BUNDLE" --profile "$pf" --frames "$f" -o "$d" "$@" >/dev/null 2>"$d.log"
}

check() { # PROFILE GRAPH FRAMES SHOT [look options]
  local pf=$1 g=$2 f=$3 shot=$4; shift 4
  local s; s=$(basename "$g" .json)
  local tag; tag=$(echo "$pf$*" | tr -cd 'a-z0-9')
  # the runner's frames, once for every host that is compared with them
  local r="$W/runner/$s.$f.$shot" o="$W/$tag/look/$s"
  local pat
  if [ -d "$r" ]; then pat=$(cat "$r.pattern")
  else
    mkdir -p "$r"
    pat=$(runner "$g" "$f" "$r" --shot "$shot") || { fail "$s: nprfx run failed: $(tail -n 2 "$r.log")"; return; }
    echo "$pat" > "$r.pattern"
  fi
  pat="$r/$pat"
  local ch; ch=$(channels_of "${pat//####/$(printf %04d ${f%-*})}")
  if ! look "$pf" "$g" "$f" "$o" --shot "$shot" --channels "$ch" "$@"; then
    fail "$s under $pf: $(grep -v 'is no look' "$o.log" | tail -n 2 | tr '\n' ' ')"; return; fi
  if same_frames "$pat" "$o" "$s" $(seq ${f%-*} ${f#*-}); then pass
  else fail "$s under $pf ($*): the look plug-in differs from nprfx run"; fi
}

# 1 -----------------------------------------------------------------------------------------------
for g in $(grep -l '"knobs"' "$SRC"/samples/graphs/*.json); do
  check strict "$g" 1-3 1-4
  check strict "$g" 1-3 1-4 --scramble --render-scale 0.5
  check natron "$g" 1-3 1-4
  check natron "$g" 1-3 1-4 --scramble
done

# 2 -----------------------------------------------------------------------------------------------
for s in toon watercolor; do check natron "$SRC/samples/graphs/$s.json" 1-6 1-8; done
check natron "$SRC/samples/graphs/toon.json" 1-6 1-8 --scramble
check strict "$SRC/samples/graphs/toon.json" 1-6 1-8 --scramble

# 3 -----------------------------------------------------------------------------------------------
T="$SRC/samples/graphs/toon.json"
mkdir -p "$W/knobs/runner"
pat=$(runner "$T" 1-2 "$W/knobs/runner" --set ink.width=3 --set bands.bands=4) && pat="$W/knobs/runner/$pat"
if look strict "$T" 1-2 "$W/knobs/look" --set ink.width=3 --set bands.bands=4 &&
   same_frames "$pat" "$W/knobs/look" toon 1 2; then pass
else fail "toon with knobs turned differs from nprfx run --set ($(tail -n 1 "$W/knobs/look.log"))"; fi
plain="$W/strictscramble/look/toon/toon.0002.exr"
if [ -f "$plain" ] && ! "$NPRFX" diff "$W/knobs/look/toon.0002.exr" "$plain" -q >/dev/null 2>&1; then pass
else fail "turning toon's knobs changed nothing"; fi

# 4 -----------------------------------------------------------------------------------------------
rm -f "$W/frames.log"
if (export NPRFX_OFXTEST_FRAMES_LOG="$W/frames.log"; look natron "$T" 1-8 "$W/inorder"); then
  wide=$(awk '$3 >= 3 && $5 - $4 > 1' "$W/frames.log" | head -n 3)
  first=$(awk '$3 == 1 && $5 - $4 > 1' "$W/frames.log" | head -n 1)
  if [ -z "$wide" ] && [ -n "$first" ]; then pass
  else fail "toon in order: declarations after frame 2 span more than t-1..t ($wide), or frame 1 not the shot ($first)"; fi
else fail "toon under natron 1-8: $(tail -n 2 "$W/inorder.log" 2>/dev/null | tr '\n' ' ')"; fi

# 5 -----------------------------------------------------------------------------------------------
if look mlt "$T" 1 "$W/mlt"; then fail "toon rendered in a host without temporal clip access"
elif grep -q "not available in this host.*temporal clip access" "$W/mlt.log"; then pass
else fail "toon under mlt: no reason given ($(tail -n 1 "$W/mlt.log"))"; fi
for g in $(grep -l '"knobs"' "$SRC"/samples/graphs/*.json); do
  s=$(basename "$g" .json)
  case $s in
  footage_*)
    r="$W/runner/$s.1-3.1-4"
    if [ ! -f "$r.pattern" ]; then fail "$s: no runner frames from section 1"; continue; fi
    pat="$r/$(cat "$r.pattern")"
    ch=$(channels_of "${pat//####/0001}")
    if ! look strict8 "$g" 1-3 "$W/byte/$s" --shot 1-4 --channels "$ch"; then
      fail "$s at 8 bits: $(tail -n 1 "$W/byte/$s.log")"; continue; fi
    for f in 1 2 3; do
      n=$(printf %04d $f)
      m=$("$NPRFX" diff "${pat//####/$n}" "$W/byte/$s/$s.$n.exr" 2>&1 | sed -n 's/^ *Mean error = //p')
      if awk -v m="$m" 'BEGIN { exit !(m != "" && m <= 0.01) }'; then pass
      else fail "$s at 8 bits, frame $f: mean error '$m' from nprfx run"; fi
    done ;;
  *)
    if look strict8 "$g" 1 "$W/byte/$s" --shot 1-2; then fail "$s rendered in an 8-bit host"
    elif grep -q "not available in this host: its clip .* carries .*8- and 16-bit" "$W/byte/$s.log"; then pass
    else fail "$s at 8 bits: no reason naming the clip ($(tail -n 1 "$W/byte/$s.log"))"; fi ;;
  esac
done

# 6 -----------------------------------------------------------------------------------------------
rm -f "$W/analyze.log"
if (export NPRFX_OFXTEST_FRAMES_LOG="$W/analyze.log"; look natron "$T" 3-5 "$W/analyzed" --analyze-shot); then
  wide=$(awk '$3 == 3 && ($4 < 1 || $5 > 3)' "$W/analyze.log" | head -n 2)
  if [ -z "$wide" ] && [ -s "$W/analyze.log" ]; then pass
  else fail "toon after Analyze Shot: frame 3 declares more than 1-3 ($wide)"; fi
  mkdir -p "$W/analyzed_runner"
  pat=$(runner "$T" 3-5 "$W/analyzed_runner") && pat="$W/analyzed_runner/$pat"
  if same_frames "$pat" "$W/analyzed" toon 3 4 5; then pass
  else fail "toon after Analyze Shot differs from nprfx run"; fi
else fail "toon with Analyze Shot: $(tail -n 2 "$W/analyzed.log" | tr '\n' ' ')"; fi

# 7 -----------------------------------------------------------------------------------------------
if look natron "$T" 1 "$W/find" --shot 1-2 --press findLayers &&
   grep -q "^depth = ViewLayer.Depth.Z$" "$W/find.log" && grep -q "^param aovLayers = " "$W/find.log"; then pass
else fail "Find AOV Layers: $(grep -A6 'param aovLayers' "$W/find.log" | head -n 6 | tr '\n' ' ')"; fi
if grep -q "^choice layer_depth = ViewLayer.Depth.Z (" "$W/find.log" &&
   grep -q "^choice layer_normal = ViewLayer.Normal.X,ViewLayer.Normal.Y,ViewLayer.Normal.Z (" "$W/find.log"; then pass
else fail "Find AOV Layers: the layer menus do not show the layers in use: $(grep '^choice layer_' "$W/find.log" | tr '\n' ' ')"; fi
R="$W/renamed"
mkdir -p "$R/plates" "$R/graphs"
for f in 1 2; do
  oiiotool "$SRC/samples/plates/crossing/crossing.000$f.exr" --chnames ",,,,ViewLayer.Zdepth.Z" \
    -o "$R/plates/crossing.000$f.exr" || fail "oiiotool could not rename the depth layer"
done
sed 's|../plates/crossing/crossing.####.exr|../plates/crossing.####.exr|' "$T" > "$R/graphs/toon.json"
echo '{"profile": "blender", "aovs": {"depth": "ViewLayer.Zdepth.Z"}}' > "$R/graphs/zmap.json"
mkdir -p "$R/runner"
pat=$(runner "$R/graphs/toon.json" 1-2 "$R/runner" --shot 1-2 --set plate.aovs=zmap.json) && pat="$R/runner/$pat"
if look natron "$R/graphs/toon.json" 1-2 "$R/look" --shot 1-2 --param "aovLayers=depth = ViewLayer.Zdepth.Z" &&
   same_frames "$pat" "$R/look" toon 1 2; then pass
else fail "toon with AOV Layers on renamed plates differs from nprfx run with the mapping: $(tail -n 1 "$R/look.log")"; fi
if look natron "$R/graphs/toon.json" 1-2 "$R/menu" --shot 1-2 --press findLayers --choose "layer_depth=ViewLayer.Zdepth.Z" &&
   grep -q "^depth = ViewLayer.Zdepth.Z$" "$R/menu.log" && same_frames "$pat" "$R/menu" toon 1 2; then pass
else fail "toon with the Depth layer menu set to ViewLayer.Zdepth.Z differs from nprfx run with the mapping: $(tail -n 1 "$R/menu.log")"; fi
for how in plain find; do
  opt=(); [ $how = find ] && opt=(--press findLayers)
  if look natron "$R/graphs/toon.json" 1 "$R/none$how" --shot 1-2 "${opt[@]}"; then fail "toon without its depth layer rendered ($how)"
  elif grep -q "input 'depth'" "$R/none$how.log"; then pass
  else fail "toon without its depth layer ($how): no reason naming the input ($(tail -n 1 "$R/none$how.log"))"; fi
done

# other renderers' names: each renderer layout of `nprfx synth` (Arnold's R,G,B,A and a bare Z,
# RenderMan's bare z and id, Karma's and V-Ray's bare depth, ...), the bare channels coming on
# the planes Nuke puts them on (Z on depth, the rest on other): toon from one Source equals the
# runner, and the Depth layer menu shows the channel the profile reads it from
for lay in arnold:depth.Z renderman:z karma:depth vray:depth redshift:depth.Z nuke:; do
  L=${lay%%:*} want=${lay#*:}
  A="$W/renderers/$L"
  mkdir -p "$A/plates" "$A/graphs" "$A/runner"
  "$NPRFX" synth orbit --layout "$L" --size 320x180 --frames 1-2 -o "$A/plates/orbit.####.exr" >/dev/null 2>&1 ||
    fail "synth --layout $L"
  sed 's|../plates/crossing/crossing.####.exr|../plates/orbit.####.exr|' "$T" > "$A/graphs/toon.json"
  pat=$(runner "$A/graphs/toon.json" 1-2 "$A/runner" --shot 1-2) && pat="$A/runner/$pat"
  if look natron "$A/graphs/toon.json" 1-2 "$A/look" --shot 1-2 --press findLayers &&
     same_frames "$pat" "$A/look" toon 1 2 &&
     { [ -z "$want" ] || grep -q "^choice layer_depth = $want (" "$A/look.log"; }; then pass
  else fail "toon on $L plates from one Source: $(grep '^choice layer_depth' "$A/look.log") $(tail -n 1 "$A/look.log")"; fi
done
if grep -q "^choice layer_beauty = R,G,B,A (" "$W/renderers/arnold/look.log"; then pass
else fail "Arnold's beauty (R,G,B,A without a layer) is not in the Beauty layer menu"; fi
if grep -q "^# depth: made by the read from Source's layers" "$W/renderers/nuke/look.log"; then pass
else fail "Nuke's 1/z depth: Find AOV Layers does not say the read makes it"; fi

# 8 -----------------------------------------------------------------------------------------------
# the version hosts key plug-ins on changes with the graph file (its minor: a hash of the bytes)
V="$W/version"
mkdir -p "$V/a"
cp "$T" "$V/a/toon.json"
sed -i 's|"../plates/|"'"$SRC"'/samples/plates/|' "$V/a/toon.json"
version_of() { grep -o 'version [0-9]*\.[0-9]*' "$1" | head -n 1; }
if look strict "$V/a/toon.json" 1 "$V/one" --shot 1-2; then
  sed -i 's/"knobs"/ "knobs"/' "$V/a/toon.json"
  if look strict "$V/a/toon.json" 1 "$V/two" --shot 1-2 && [ -n "$(version_of "$V/one.log")" ] &&
     [ "$(version_of "$V/one.log")" != "$(version_of "$V/two.log")" ]; then pass
  else fail "the look's version did not change with its graph file: $(version_of "$V/one.log"), $(version_of "$V/two.log")"; fi
else fail "toon from another folder: $(tail -n 1 "$V/one.log")"; fi

# 9 -----------------------------------------------------------------------------------------------
M="$SRC/samples/graphs/main.json"
mkdir -p "$W/writers/runner"
if "$NPRFX" run "$M" --frames 1-4 --shot 1-5 --output-dir "$W/writers/runner" --quiet --threads 2 >/dev/null 2>"$W/writers/runner.log" &&
   look natron "$M" 1-4 "$W/writers/look" --shot 1-5 --outputs all --channels "R,G,B,A;Y"; then
  bad=""
  for f in 1 2 3 4; do
    for w in pencil noise; do
      "$NPRFX" diff "$W/writers/runner/out/main/$w.000$f.exr" "$W/writers/look/main.w_$w.000$f.exr" \
        --fail 0 --hardfail 0 --warn 0 -q >/dev/null 2>&1 || bad="$bad $w.$f"
    done
  done
  if [ -z "$bad" ]; then pass; else fail "two looks at once differ from nprfx run:$bad"; fi
else fail "main.json's two outputs at once: $(tail -n 2 "$W/writers/look.log" "$W/writers/runner.log" | tr '\n' ' ')"; fi

echo "$passes passed, $fails failed"
[ $fails -eq 0 ] && [ $passes -gt 0 ]
