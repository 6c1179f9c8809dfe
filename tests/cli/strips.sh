#!/usr/bin/env bash
# Strip renders (docs/design.md §1 "Memory"): a write whose chain renders by rows
# (reads of EXRs; blend, threshold-map, morphology, warp with a reach) goes a strip of rows at a
# time.
#   - the pixels are the whole frame's, bit for bit, at any strip height (1 row, 7 rows against
#     filters reaching 6 rows, 64, taller than the frame), chained filters included, and a plate
#     written through strips keeps its channels' file types; no temporary file is left; writes
#     whose chains share nodes go together, each shared node rendering a strip once;
#   - a 4K (3840x2160) graph renders under a --mem-limit below one frame of its plate's
#     channels, by strips the plan chooses itself, identical to the whole-frame render without a
#     limit, in a fraction of its peak resident memory;
#   - a limit even strips pass is refused before rendering, naming both needs; a graph that
#     cannot render by rows is refused as before, saying which node is in the way.
#
# usage: bash strips.sh NPRFX_BINARY SOURCE_DIR WORK_DIR
set -u
NPRFX=$1; W=$3
rm -rf "$W"; mkdir -p "$W"; cd "$W" || exit 1
passes=0; fails=0
pass() { passes=$((passes+1)); }
fail() { echo "FAIL: $*"; fails=$((fails+1)); }
same() { # A B: the same pixels, bit for bit
  "$NPRFX" diff "$1" "$2" --fail 0 --hardfail 0 --warn 0 >/dev/null 2>&1
}

# ---- small plates, every strip height ---------------------------------------------------------
"$NPRFX" synth orbit --frames 1-2 --size 320x180 --half -o plates/o.####.exr >/dev/null 2>&1 ||
  fail "synth plates"
# morph2 reads morph1 3 rows away (close, radius 3), morph1 reads the plate 2 rows away: the
# plate's strips need 5 rows of margin, morph1's 3.
cat > chain.json <<'EOF'
{"frames": "1-2", "nodes": {
 "plate": {"node": "read", "path": "plates/o.####.exr"},
 "morph1": {"node": "morphology", "inputs": {"image": "plate:R,G,B"}, "params": {"operation": "dilate", "radius": 2}},
 "morph2": {"node": "morphology", "inputs": {"image": "morph1"}, "params": {"operation": "close", "radius": 1.5, "footprint": "square"}},
 "thr": {"node": "threshold-map", "inputs": {"pattern": "plate:G", "tone": "plate:B"}, "params": {"mode": "builtin", "sigma": 8}},
 "look": {"node": "blend", "inputs": {"base": "morph2", "layer": "plate:R,G,B", "alpha": "thr"}, "params": {"mode": "alphablend"}},
 "w_look": {"node": "write", "inputs": {"image": "look"}, "path": "out/look.####.exr", "half": true},
 "w_plate": {"node": "write", "inputs": {"image": "plate:R,G,B,A"}, "path": "out/plate.####.exr"},
 "w_morph": {"node": "write", "inputs": {"image": "morph2"}, "path": "out/morph.####.exr"}
}}
EOF
"$NPRFX" run chain.json --threads 2 -q --output-dir whole --strip-rows -1 --stats > whole.txt 2> whole.err ||
  fail "whole-frame render: $(cat whole.err)"
grep -q "rendered by strips" whole.txt && fail "--strip-rows -1 rendered by strips"
for rows in 1 7 64 1000; do
  "$NPRFX" run chain.json --threads 2 -q --output-dir s$rows --strip-rows $rows --stats > s$rows.txt 2> s$rows.err ||
    { fail "--strip-rows $rows: $(cat s$rows.err)"; continue; }
  grep -q "^rendered by strips of $rows rows" s$rows.txt && pass || fail "--strip-rows $rows: no strips in --stats: $(tail -2 s$rows.txt)"
  n=0
  for f in whole/out/*.exr; do
    n=$((n+1))
    same "$f" "s$rows/${f#whole/}" || fail "--strip-rows $rows: $(basename "$f") differs from the whole-frame render"
  done
  [ $n -eq 6 ] && pass || fail "the whole-frame render wrote $n files, not 6"
  left=$(find s$rows -name '.*tmp*' | head -1)
  [ -z "$left" ] && pass || fail "--strip-rows $rows left a temporary file: $left"
done
# The three writes share the plate (all of them) and morph1/morph2 (w_look, w_morph): a strip of
# each node is made once for all of them, so each renders once a frame, not once per write.
for n in plate morph1 morph2 thr look; do
  awk -v n="$n" '$1 == n && $3 == 2 { ok = 1 } END { exit !ok }' s7.txt && pass ||
    fail "strips: $n did not render once a frame: $(grep "^  $n " s7.txt)"
done
# A plate written through strips keeps its channels' file types (half here), as a whole write.
"$NPRFX" info s7/out/plate.0001.exr | grep -q "R G B A (half)" && pass ||
  fail "strips: the plate's half channels were not written as half: $("$NPRFX" info s7/out/plate.0001.exr)"
# The filters do reach across strips: rendering them without their margins would differ.
sed 's/"radius": 2}/"radius": 0}/' chain.json > chain0.json
"$NPRFX" run chain0.json --threads 2 -q --output-dir r0 --strip-rows 7 2>/dev/null
same whole/out/morph.0001.exr r0/out/morph.0001.exr && fail "the diff cannot tell a dilation from none" || pass
same whole/out/look.0001.exr r0/out/look.0001.exr && fail "the look does not show the filters" || pass

# A warp with a reach renders by rows too: the image rows within reach (plus the filter's taps)
# of the strip; bicubic reads two rows beyond the floor. Without a reach its footprint is the
# whole frame, and the same graph renders whole frames.
cat > warp.json <<'EOF'
{"frames": "1-2", "nodes": {
 "plate": {"node": "read", "path": "plates/o.####.exr"},
 "wp": {"node": "warp", "inputs": {"image": "plate:R,G,B", "offset": "plate:motion_prev.X,motion_prev.Y"},
        "params": {"amount": 3, "reach": 4.5, "filter": "bicubic"}},
 "w": {"node": "write", "inputs": {"image": "wp"}, "path": "out/warp.####.exr"}
}}
EOF
"$NPRFX" run warp.json --threads 2 -q --output-dir ww --strip-rows -1 2> ww.err || fail "warp, whole frames: $(cat ww.err)"
for rows in 1 5 64; do
  "$NPRFX" run warp.json --threads 2 -q --output-dir ws$rows --strip-rows $rows --stats > ws$rows.txt 2> ws$rows.err ||
    { fail "warp, --strip-rows $rows: $(cat ws$rows.err)"; continue; }
  grep -q "^rendered by strips of $rows rows" ws$rows.txt && pass || fail "warp with a reach, --strip-rows $rows: no strips: $(tail -2 ws$rows.txt)"
  same ww/out/warp.0002.exr ws$rows/out/warp.0002.exr && pass || fail "warp, --strip-rows $rows: differs from the whole frame"
done
sed 's/"amount": 3, "reach": 4.5, /"amount": 3, /' warp.json > warp0.json
"$NPRFX" run warp0.json --threads 2 -q --output-dir w0 --strip-rows 5 --stats > w0.txt 2> w0.err || fail "warp without reach: $(cat w0.err)"
grep -q "rendered by strips" w0.txt && fail "a warp without a reach rendered by strips" || pass
# The reach binds: the orbit moves up to ~6 px a frame at this size, so an unbounded warp differs.
same ww/out/warp.0002.exr w0/out/warp.0002.exr && fail "reach 4.5 changed nothing: the test cannot see it" || pass

# ---- 4K ---------------------------------------------------------------------------------------
# A plate of 4 half channels (one frame of them as floats: 127 MiB), made by the paper node.
cat > mk4k.json <<'EOF'
{"frames": "1", "format": "3840x2160", "nodes": {"paper": {"node": "paper", "params": {"kind": "watercolor"}},
 "w": {"node": "write", "inputs": {"image": "paper"}, "path": "p4k/p.####.exr", "half": true}}}
EOF
"$NPRFX" run mk4k.json --threads 2 -q 2> mk.err || fail "4K plate: $(cat mk.err)"
cat > g4k.json <<'EOF'
{"frames": "1", "nodes": {
 "plate": {"node": "read", "path": "p4k/p.####.exr"},
 "morph": {"node": "morphology", "inputs": {"image": "plate:R,G,B"}, "params": {"operation": "open", "radius": 3}},
 "thr": {"node": "threshold-map", "inputs": {"pattern": "plate:A"}, "params": {"mode": "erf", "sigma": 8}},
 "look": {"node": "blend", "inputs": {"base": "morph", "layer": "plate:R,G,B", "alpha": "thr"}, "params": {"mode": "alphablend"}},
 "w": {"node": "write", "inputs": {"image": "look"}, "path": "out/look.####.exr", "half": true}
}}
EOF
/usr/bin/time -f %M -o whole4k.kib "$NPRFX" run g4k.json --threads 2 -q --output-dir w8 --mem-limit 0 --stats > w8.txt 2> w8.err ||
  fail "4K whole-frame render: $(cat w8.err)"
grep -q "rendered by strips" w8.txt && fail "4K without a limit rendered by strips"
/usr/bin/time -f %M -o strip4k.kib "$NPRFX" run g4k.json --threads 2 -q --output-dir s8 --mem-limit 96M --stats > s8.txt 2> s8.err ||
  fail "4K under --mem-limit 96M: $(cat s8.err)"
grep -q "^rendered by strips of 64 rows" s8.txt && pass || fail "4K under 96M: not by strips: $(tail -2 s8.txt)"
same w8/out/look.0001.exr s8/out/look.0001.exr && pass || fail "4K: the strip render differs from the whole-frame render"
kw=$(tail -1 whole4k.kib); ks=$(tail -1 strip4k.kib)
echo "4K peak resident: whole frames $((kw / 1024)) MiB, strips $((ks / 1024)) MiB"
# The plate alone is 127 MiB as floats; the process itself (libraries, the dot sequence) takes
# what the same graph takes on a 64x64 plate. Above that, strips must hold less than a third of
# what whole frames hold (measured: 62 against 380 MiB), and stay under 200 MiB in all.
sed 's|"format": "3840x2160"|"format": "64x64"|; s|p4k/|p64/|' mk4k.json > mk64.json
sed 's|p4k/|p64/|' g4k.json > g64.json
"$NPRFX" run mk64.json --threads 2 -q 2> mk.err || fail "64x64 plate: $(cat mk.err)"
/usr/bin/time -f %M -o base.kib "$NPRFX" run g64.json --threads 2 -q --output-dir b64 2> b64.err ||
  fail "64x64 render: $(cat b64.err)"
kb=$(tail -1 base.kib)
echo "the process on a 64x64 plate: $((kb / 1024)) MiB"
if [ -n "${NPRFX_SANITIZED:-}" ]; then
  echo "skip: 4K resident bounds (AddressSanitizer build: its quarantine and shadow set the resident size)"
else
  [ "$ks" -lt $((200 * 1024)) ] && [ $((ks - kb)) -lt $(((kw - kb) / 3)) ] && pass ||
    fail "4K strips took $((ks / 1024)) MiB (whole frames $((kw / 1024)) MiB, the process alone $((kb / 1024)) MiB)"
fi

# ---- refusals ---------------------------------------------------------------------------------
"$NPRFX" run g4k.json -q --output-dir r8 --mem-limit 20M 2> r8.err
rc=$?
[ $rc -eq 2 ] && pass || fail "4K under 20M: exit $rc, not 2"
grep -Eq "frame 1 needs [0-9]+ MiB of frames whole, and still [0-9.]+ MiB in strips of 64 rows \(write node 'w' and the nodes it reads, 3840x2160\): above the 20 MiB memory limit \(--mem-limit\); nothing was rendered" r8.err && pass ||
  fail "4K under 20M: $(cat r8.err)"
[ ! -e r8 ] && pass || fail "4K under 20M wrote something"
# Below even one block of rows of the plate (3840x64 of 4 floats, 3.8 MiB).
"$NPRFX" run g4k.json -q --output-dir r1 --mem-limit 1M 2> r1.err
rc=$?
[ $rc -eq 2 ] && grep -q "and strips of 64 rows do not fit either: .*'p4k/p.0001.exr': a block of rows 3840x64 with 4 channels needs 3.8 MiB, above the 1 MiB memory limit (--mem-limit); nothing was rendered" r1.err &&
  pass || fail "4K under 1M: exit $rc: $(cat r1.err)"
cat > noise.json <<'EOF'
{"frames": "1", "nodes": {
 "plate": {"node": "read", "path": "plates/o.####.exr"},
 "noise": {"node": "coherent-noise", "inputs": {"depth": "plate:Z", "motion_prev": "plate:motion_prev.X,motion_prev.Y"}},
 "w": {"node": "write", "inputs": {"image": "noise"}, "path": "out/n.####.exr"}
}}
EOF
"$NPRFX" run noise.json -q --output-dir rn --mem-limit 300K 2> rn.err
rc=$?
[ $rc -eq 2 ] && grep -q "nothing was rendered (nor can it render by strips of rows: node 'noise' (coherent-noise) needs its inputs' whole frames)" rn.err &&
  pass || fail "a graph that cannot render by rows, over the limit: exit $rc: $(cat rn.err)"
rm -rf p4k w8 s8

echo "strips: $passes passed, $fails failed"
[ $fails -eq 0 ]
