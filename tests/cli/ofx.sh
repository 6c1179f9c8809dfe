#!/usr/bin/env bash
# The OpenFX path: the bundle exports exactly OfxGetNumberOfPlugins and OfxGetPlugin,
# holds one plug-in per node of `nprfx list`, and every test graph (and every sample graph whose
# inputs are synthetic or present in the repository) renders bit-identically through the
# plug-ins (`nprfx-ofxtest run --ofx BUNDLE`, the test host of tests/ofxhost/) and directly
# (`nprfx run`).
# The OFX renders use tiles and 3 threads, so render windows differ from image bounds and the
# host's multithread suite is exercised.
#
# usage: NPRFX_OFXTEST=TEST_HOST_BINARY bash ofx.sh NPRFX_BINARY SOURCE_DIR WORK_DIR
# (ctest sets NPRFX_OFXTEST to the nprfx-ofxtest it built)
set -u
NPRFX=$1; SRC=$2; W=$3
OFXTEST=${NPRFX_OFXTEST:-}
BUNDLE=$(cd "$(dirname "$NPRFX")" && pwd)/plugins/ofx/nprfx.ofx.bundle
rm -rf "$W"; mkdir -p "$W"
W=$(cd "$W" && pwd); SRC=$(cd "$SRC" && pwd) # absolute: the test host runs from its output folder
passes=0; fails=0
pass() { passes=$((passes+1)); }
fail() { echo "FAIL: $*"; fails=$((fails+1)); }

BIN=$(ls "$BUNDLE"/Contents/*/nprfx.ofx 2>/dev/null | head -n 1)
if [ -z "$BIN" ]; then
  echo "FAIL: no bundle binary under $BUNDLE/Contents/*/nprfx.ofx"
  exit 1
fi
if [ -z "$OFXTEST" ] || [ ! -x "$OFXTEST" ]; then
  echo "FAIL: no test host: NPRFX_OFXTEST='$OFXTEST' is not an executable nprfx-ofxtest"
  exit 1
fi

# --- the exported symbols: the two entry points and nothing else -----------------------------
defined=$(nm -D --defined-only "$BIN" | awk '{print $NF}' | sort | tr '\n' ' ')
if [ "$defined" = "OfxGetNumberOfPlugins OfxGetPlugin " ]; then pass
else fail "nm -D --defined-only $BIN shows: $defined (want exactly OfxGetNumberOfPlugins OfxGetPlugin)"; fi
for sym in OfxGetNumberOfPlugins OfxGetPlugin; do
  if nm -D "$BIN" | grep -q " T $sym\$"; then pass; else fail "nm -D does not show $sym"; fi
done

# --- one plug-in per node (nprfx list also shows the I/O pseudo-nodes read and write), and one
# per look the bundle ships (the sample graphs that name their knobs; tests/cli/ofx_looks.sh) ---
nodes=$("$NPRFX" list | awk '$2 != "I/O"' | wc -l)
looks=$(grep -l '"knobs"' "$SRC"/samples/graphs/*.json | wc -l)
cat > "$W/count.json" <<'EOF'
{"frames": "1", "nodes": {"p": {"node": "synth", "scene": "translate", "size": "8x8"},
 "w": {"node": "write", "inputs": {"image": "p"}, "path": "count.####.exr"}}}
EOF
line=$("$OFXTEST" run "$W/count.json" --output-dir "$W/count" --ofx "$BUNDLE" 2>&1 >/dev/null | grep '^ofx: ')
plugins=$(echo "$line" | sed -n 's/^ofx: \([0-9]*\) plug-ins.*/\1/p')
if [ -n "$plugins" ] && [ "$plugins" -eq $((nodes + looks)) ] && [ "$nodes" -gt 0 ] && [ "$looks" -gt 0 ]; then pass
else fail "the bundle has '${plugins:-?}' plug-ins, nprfx list has $nodes nodes and samples/graphs $looks looks ($line)"; fi

# --- the shipped runner holds no OpenFX host: no --ofx option, none of the host's code ----------
"$NPRFX" run "$W/count.json" --output-dir "$W/count" --ofx "$BUNDLE" > "$W/runner.out" 2>&1
rc=$?
if [ $rc -eq 2 ] && grep -q "unexpected argument '--ofx'" "$W/runner.out"; then pass
else fail "nprfx run --ofx: exit $rc, want 2 and 'unexpected argument' (the host is nprfx-ofxtest's)"; fi
# (the runner does derive OpenFX names, for host-project's files: the option table of
# ofx_names.h is allowed; the host's suites and the plug-in entry points are not)
host_syms=$(nm "$NPRFX" 2>/dev/null |
            grep -cE 'nprfx_ofx_host|internal_(fetch_suite|image_effect_suite|parameter_suite|property_suite)|OfxGetPlugin|OfxGetNumberOfPlugins')
if [ "$host_syms" -eq 0 ]; then pass; else fail "nm $NPRFX shows $host_syms OpenFX host symbols"; fi
# the check can see them: the test host has them
if [ "$(nm "$OFXTEST" 2>/dev/null | grep -cE 'internal_fetch_suite|nprfx_ofx_host_open')" -gt 0 ]; then pass
else fail "nm $OFXTEST shows no host symbols: the check above cannot see them"; fi

# --- graphs -----------------------------------------------------------------------------------
# A sample graph qualifies when every read node's files exist for the graph's frames.
inputs_present() {
  local g=$1 dir frames first last paths p f file
  dir=$(dirname "$g")
  frames=$(grep -o '"frames": *"[^"]*"' "$g" | head -n 1 | sed 's/.*"\([^"]*\)"$/\1/')
  first=${frames%%-*}; last=${frames##*-}
  case "$first$last" in ''|*[!0-9]*) first=1; last=1 ;; esac
  paths=$(tr '\n' ' ' < "$g" | grep -o '{[^{}]*"node": *"read"[^{}]*}' |
          grep -o '"path": *"[^"]*"' | sed 's/.*"\([^"]*\)"$/\1/')
  for p in $paths; do
    case "$p" in /*) ;; *) p="$dir/$p" ;; esac
    for f in $(seq "$first" "$last"); do
      file=$(echo "$p" | sed -e "s/####/$(printf %04d "$f")/" -e "s/%04d/$(printf %04d "$f")/")
      [ -f "$file" ] || return 1
    done
  done
  return 0
}

graphs=$(ls "$SRC"/tests/graphs/*.json 2>/dev/null)
for g in $(ls "$SRC"/samples/graphs/*.json 2>/dev/null); do
  if inputs_present "$g"; then graphs="$graphs $g"
  else echo "skip: $g (its plates are not in the repository)"; fi
done

# Sample graphs are whole shots: their first 6 frames are enough here (temporal nodes still see
# the whole shot, so frame 6 of a symmetric recursion involves every frame).
frame_limit() {
  local g=$1 frames first last
  case "$g" in "$SRC"/samples/*) ;; *) return 0 ;; esac
  frames=$(grep -o '"frames": *"[0-9]*-[0-9]*"' "$g" | head -n 1 | grep -o '[0-9]*-[0-9]*')
  [ -n "$frames" ] || return 0
  first=${frames%%-*}; last=${frames##*-}
  [ "$last" -gt $((first + 5)) ] && last=$((first + 5))
  echo "--frames $first-$last"
}

. "$SRC/tests/lib/flow.sh"
ngraphs=0
for g in $graphs; do
  needs_missing_flow "$NPRFX" "$g" && { echo "skip: $g (no optical flow in this build)"; continue; }
  name=$(basename "$(dirname "$g")")_$(basename "$g" .json)
  out="$W/$name"
  limit=$(frame_limit "$g")
  if ! "$NPRFX" run "$g" $limit --output-dir "$out/direct" --quiet; then
    fail "$g: direct render"; continue
  fi
  # From inside the output folder: a plug-in writes a relative export path (stipple's SVG) from
  # the host's working folder, where the runner writes it under --output-dir.
  mkdir -p "$out/ofx"
  if ! (cd "$out/ofx" && "$OFXTEST" run "$g" $limit --output-dir "$out/ofx" --quiet \
          --ofx "$BUNDLE" --tile 37 --threads 3); then
    fail "$g: render through $BUNDLE"; continue
  fi
  ngraphs=$((ngraphs+1))
  files=$(cd "$out/direct" && find . -name '*.exr' | sort)
  [ -n "$files" ] || fail "$g wrote no EXR"
  for f in $(cd "$out/direct" && find . -name '*.svg' -o -name '*.csv' | sort); do
    if cmp -s "$out/direct/$f" "$out/ofx/$f"; then pass
    else fail "$g: the export $f differs between the runner and the plug-in (or is missing)"; fi
  done
  for f in $files; do
    if [ ! -f "$out/ofx/$f" ]; then fail "$g: $f missing from the OFX render"; continue; fi
    if "$NPRFX" diff "$out/direct/$f" "$out/ofx/$f" --fail 0 --hardfail 0 --warn 0 >/dev/null 2>&1; then
      pass
    else
      fail "$g: $f differs between the direct and the OFX render"
      "$NPRFX" diff "$out/direct/$f" "$out/ofx/$f" --fail 0 --hardfail 0 --warn 0
    fi
  done
done
[ "$ngraphs" -gt 0 ] || fail "no graph rendered"

echo "$passes passed, $fails failed ($ngraphs graphs)"
[ $fails -eq 0 ] && [ $passes -gt 0 ]
