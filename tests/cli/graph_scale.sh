#!/usr/bin/env bash
# Graphs of any size give a result or a clear error, never a signal: a 100,000-node chain, a
# lattice of 20 diamonds (2^20 paths from the plate to the write), cycles hidden at the end of a
# long chain and behind the lattice's fan-out, and a 30,000-node chain validated in well under a
# second. The time bounds are generous for a loaded 2-core machine.
set -u
NPRFX=$1; SRC=$2; W=$3
rm -rf "$W"; mkdir -p "$W"; cd "$W"
fails=0; passes=0
fail() { fails=$((fails+1)); echo "FAIL: $*"; }

now_ms() { echo $(( $(date +%s%N) / 1000000 )); }

# run_bounded NAME WANT PATTERN MAX_MS -- command...: exit status WANT, stderr containing PATTERN
# (empty: anything), at most MAX_MS milliseconds; a status over 128 (a signal) always fails.
# The time taken is left in $took.
run_bounded() {
  local name=$1 want=$2 pattern=$3 max=$4; shift 5
  local t0; t0=$(now_ms)
  "$@" >"$name.out" 2>"$name.err"; local st=$?
  took=$(( $(now_ms) - t0 ))
  echo "$name: exit $st in $took ms"
  if [ $st -gt 128 ]; then fail "$name died with signal $((st-128))"; cat "$name.err"; return; fi
  if [ $st -ne "$want" ]; then fail "$name exited $st (want $want)"; cat "$name.err"; return; fi
  if [ -n "$pattern" ] && ! grep -qF -- "$pattern" "$name.err"; then
    fail "$name: stderr lacks '$pattern'"; cat "$name.err"; return
  fi
  if [ "$took" -gt "$max" ]; then fail "$name took $took ms (bound $max)"; return; fi
  passes=$((passes+1))
}

# chain N FIRST: plate -> m1 -> ... -> mN -> write, where m1 reads FIRST (plate:R, or mN to close
# a cycle through every node).
chain() {
  awk -v n="$1" -v first="$2" 'BEGIN {
    printf "{\"frames\": \"1\", \"nodes\": {\n"
    printf "\"plate\": {\"node\": \"synth\", \"scene\": \"orbit\", \"size\": \"4x4\"},\n"
    prev = first
    for (i = 1; i <= n; i++) {
      printf "\"m%d\": {\"node\": \"morphology\", \"inputs\": {\"image\": \"%s\"}},\n", i, prev
      prev = "m" i
    }
    printf "\"w\": {\"node\": \"write\", \"inputs\": {\"image\": \"%s\"}, \"path\": \"o/chain.####.exr\"}}}\n", prev
  }'
}

# lattice N FIRST: j0 reads FIRST; diamond i splits j(i-1) into a dilation l_i and an erosion r_i
# and blends them into j_i, so there are 2^N paths from j0 to jN.
lattice() {
  awk -v n="$1" -v first="$2" 'BEGIN {
    printf "{\"frames\": \"1\", \"nodes\": {\n"
    printf "\"plate\": {\"node\": \"synth\", \"scene\": \"orbit\", \"size\": \"4x4\"},\n"
    printf "\"j0\": {\"node\": \"morphology\", \"inputs\": {\"image\": \"%s\"}},\n", first
    for (i = 1; i <= n; i++) {
      p = "j" (i - 1)
      printf "\"l%d\": {\"node\": \"morphology\", \"inputs\": {\"image\": \"%s\"}},\n", i, p
      printf "\"r%d\": {\"node\": \"morphology\", \"inputs\": {\"image\": \"%s\"}, ", i, p
      printf "\"params\": {\"operation\": \"erode\"}},\n"
      printf "\"j%d\": {\"node\": \"blend\", \"inputs\": {\"base\": \"l%d\", \"layer\": \"r%d\"}},\n", i, i, i
    }
    printf "\"w\": {\"node\": \"write\", \"inputs\": {\"image\": \"j%d\"}, \"path\": \"o/lattice.####.exr\"}}}\n", n
  }'
}

chain 100000 plate:R > chain100k.json
run_bounded chain100k 0 "" 60000 -- "$NPRFX" run chain100k.json --quiet
[ -f o/chain.0001.exr ] && passes=$((passes+1)) || fail "the 100,000-node chain wrote nothing"

lattice 20 plate:R > lattice.json
run_bounded lattice 0 "" 30000 -- "$NPRFX" run lattice.json --quiet
[ -f o/lattice.0001.exr ] && passes=$((passes+1)) || fail "the lattice wrote nothing"

# A cycle behind 2^20 paths is found, and the message names the nodes on it.
lattice 20 j20 > lattice_cycle.json
run_bounded lattice_cycle 2 "the graph has a cycle: j0 -> l1 -> j1 -> " 30000 \
  -- "$NPRFX" run lattice_cycle.json --quiet

chain 100000 m100000 > chain_cycle.json
run_bounded chain_cycle 2 "the graph has a cycle: m1 -> m2 -> m3" 60000 \
  -- "$NPRFX" run chain_cycle.json --quiet

# Validation alone (a cycle closed at the end fails after every check has run) of a 30,000-node
# chain, less the runner's start-up, measured on a 1-node graph failing the same way.
chain 1 m1 > chain1_cycle.json
run_bounded chain1_cycle 2 "the graph has a cycle: m1 -> m1" 30000 \
  -- "$NPRFX" run chain1_cycle.json --quiet
base=$took
chain 30000 m30000 > chain30k_cycle.json
run_bounded chain30k_cycle 2 "the graph has a cycle: m1 -> m2" 60000 \
  -- "$NPRFX" run chain30k_cycle.json --quiet
echo "validating 30,000 nodes: $((took - base)) ms beyond start-up"
[ $((took - base)) -lt 5000 ] && passes=$((passes+1)) ||
  fail "validating 30,000 nodes took $((took - base)) ms beyond start-up (bound 5000; it took minutes before)"

echo "$passes passed, $fails failed"
[ $fails -eq 0 ]
