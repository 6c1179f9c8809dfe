#!/usr/bin/env bash
# The graph loader on what fuzz_graph found (tests/data/regressions/graph/) and on every sample
# and test graph: `nprfx run --check` exits 0, or 2 with a message naming what is wrong, never
# with a signal (and, in a sanitizer build, never with a leak or a memory error: ASan exits 1).
set -u
NPRFX=$1; SRC=$2; W=$3
rm -rf "$W"; mkdir -p "$W"; cd "$W"
fails=0; n=0
fail() { fails=$((fails+1)); echo "FAIL: $*"; }

check() { # FILE WANT_STATUS [TEXT]
  local f=$1 want=$2 text=${3:-}
  n=$((n+1))
  "$NPRFX" run --check "$f" >out.txt 2>err.txt; local st=$?
  if [ $st -ge 128 ]; then fail "$f: signal $((st-128))"; cat err.txt; return; fi
  if [ "$want" = any ]; then
    [ $st -eq 0 ] || [ $st -eq 2 ] || { fail "$f: exit $st (want 0 or 2)"; cat err.txt; return; }
    [ $st -eq 0 ] || [ -s err.txt ] || fail "$f: exit 2 without a message"
  elif [ $st -ne "$want" ]; then fail "$f: exit $st (want $want)"; cat err.txt; return; fi
  if [ -n "$text" ] && ! grep -qF -- "$text" err.txt; then
    fail "$f: message lacks '$text'"; cat err.txt
  fi
}

# Every graph the project ships checks clean.
for f in "$SRC"/samples/graphs/*.json "$SRC"/tests/graphs/*.json; do check "$f" 0; done
# The fuzzer's findings: the expected message where one is recorded, else a clean verdict.
R="$SRC/tests/data/regressions/graph"
for f in "$R"/*; do
  [ -f "$f" ] || continue
  b=$(basename "$f"); [ "$b" = EXPECT ] && continue
  text=$(awk -F'\t' -v b="$b" '$1 == b {print $2}' "$R/EXPECT" 2>/dev/null)
  if [ -n "$text" ]; then check "$f" 2 "$text"; else check "$f" any; fi
done
# Keys given twice are refused (JSON leaves them to the reader), naming the key.
printf '{"frames": "1", "frames": "2", "nodes": {}}' >dup.json
check dup.json 2 "top-level entry 'frames' is given twice"
printf '{"nodes": {}, "nodes": {}}' >dup2.json
check dup2.json 2 "top-level entry 'nodes' is given twice"

printf '{"nodes": {"p": {"node": "synth", "scene": "orbit", "size": "8x8"}, "m": {"node": "morphology", "inputs": {"image": "p"}, "params": {"radius": 1, "radius": 2}}, "w": {"node": "write", "inputs": {"image": "m"}, "path": "x.exr"}}}' >dup3.json
check dup3.json 2 "node 'm': param 'radius' is given twice"

echo "$n graphs checked, $fails failures"
[ $fails -eq 0 ]
