#!/usr/bin/env bash
# The runner's frame pool and memory plan, on the six-node pipeline of
# samples/bench/bench_six.json at a small size:
#   - pixels are bit-identical with and without the pool (--no-pool), at a memory limit just
#     above the plan's estimate, with a cache so small that results are evicted and rendered
#     again, and in reverse frame order;
#   - the plan frees: the frames held at once stay near the estimate, below what the cache alone
#     held, and the plate's buffers are reused instead of allocated every frame;
#   - a graph needing more than --mem-limit fails before its first frame, naming the node and
#     the sizes, writing nothing;
#   - the forms of `run --stats` and `bench-graph`;
#   - an input that gathers its own channels (NPRFX_INPUT_IN_PLACE: gabor-splat's anchor, depth
#     and id) reads them in place out of a wide plate, with no packed copy.
#
# usage: bash pool.sh NPRFX_BINARY SOURCE_DIR WORK_DIR
set -u
NPRFX=$1; SRC=$2; W=$3
rm -rf "$W"; mkdir -p "$W"; cd "$W" || exit 1
passes=0; fails=0
pass() { passes=$((passes+1)); }
fail() { echo "FAIL: $*"; fails=$((fails+1)); }
num='[0-9]+(\.[0-9]+)?'

sed -e 's/1920x1080/160x90/' -e 's/"1-8"/"1-5"/' "$SRC/samples/bench/bench_six.json" > six.json
render() { # DIR OPTIONS...: render six.json under DIR with --stats into DIR.txt
  local d=$1; shift
  "$NPRFX" run six.json --threads 2 --output-dir "$d" --stats -q "$@" > "$d.txt" 2> "$d.err"
  local rc=$?
  [ $rc -eq 0 ] && pass || { fail "run $* exited $rc: $(cat "$d.err")"; }
}
same() { # DIR: every frame under DIR equals the pooled one, bit for bit
  local n=0
  for f in pool/out/bench_six/*.exr; do
    n=$((n+1))
    if "$NPRFX" diff "$f" "$1/${f#pool/}" --fail 0 --hardfail 0 --warn 0 >/dev/null 2>&1; then :
    else fail "$1: $(basename "$f") differs from the pooled run"; return; fi
  done
  [ $n -eq 5 ] && pass || fail "the pooled run wrote $n frames, not 5"
}
held() { sed -n "s/^frames and caches held at most \([0-9.]*\) \([KMG]\)iB.*/\1 \2/p" "$1.txt" | awk '{ print $1 * ($2 == "K" ? 1 / 1024 : $2 == "G" ? 1024 : 1) }'; }
estimate() { sed -n "s/^frames and caches held at most .*(estimate \([0-9.]*\) \([KMG]\)iB,.*/\1 \2/p" "$1.txt" | awk '{ print $1 * ($2 == "K" ? 1 / 1024 : $2 == "G" ? 1024 : 1) }'; }
need() { sed -n "s/^frames and caches held at most .*, \([0-9.]*\) \([KMG]\)iB in use at once;.*/\1 \2/p" "$1.txt" | awk '{ print $1 * ($2 == "K" ? 1 / 1024 : $2 == "G" ? 1024 : 1) }'; }
caches() { sed -n "s/^of the estimate, up to \([0-9.]*\) \([KMG]\)iB are caches nodes keep between frames$/\1 \2/p" "$1.txt" | awk '{ print $1 * ($2 == "K" ? 1 / 1024 : $2 == "G" ? 1024 : 1) }'; }
column() { awk -v n="$2" -v c="$3" '$1 == n { print $c }' "$1.txt"; } # DIR NODE COLUMN

render pool
render nopool --no-pool
same nopool
render reverse --frames 5-1
same reverse
render evict --cache-mb 16 --frames 3,1,5,2,4
same evict

# The same graph over the same plates read from files (float EXRs, so the pixels are the same):
# a reader's buffers, trimmed to what is read, go back to the system, not to the pool.
"$NPRFX" synth orbit --frames 1-5 --size 160x90 -o plates/orbit.####.exr > /dev/null 2>&1 || fail "synth plates"
sed 's|"plate": {"node": "synth", "scene": "orbit", "size": "160x90"}|"plate": {"node": "read", "path": "plates/orbit.####.exr"}|' six.json > six_read.json
grep -q '"node": "read"' six_read.json || fail "six_read.json has no read node"
for v in pool nopool; do
  "$NPRFX" run six_read.json --threads 2 --output-dir read_$v -q $([ $v = nopool ] && echo --no-pool) 2> read.err || fail "six_read.json ($v): $(cat read.err)"
done
n=0
for f in read_pool/out/bench_six/*.exr; do
  n=$((n+1))
  "$NPRFX" diff "$f" "read_nopool/${f#read_pool/}" --fail 0 --hardfail 0 --warn 0 >/dev/null 2>&1 ||
    { fail "read plates: $(basename "$f") differs with and without the pool"; break; }
  "$NPRFX" diff "$f" "pool/${f#read_pool/}" --fail 0 --hardfail 0 --warn 0 >/dev/null 2>&1 ||
    { fail "read plates: $(basename "$f") differs from the render of the same plates made in memory"; break; }
done
[ $n -eq 5 ] && pass || fail "read plates: $n frames"

# --- the plan frees and the pool reuses -------------------------------------------------------
est=$(estimate pool); hp=$(held pool); hn=$(held nopool); kept=$(caches pool)
[ -n "$est" ] && [ -n "$hp" ] && [ -n "$hn" ] || fail "no 'frames and caches held' line: $(cat pool.txt)"
# coherent-noise's pass states, as its state_bytes counts them for 5 frames of 160x90 with the
# default cache_mb: ceil(sqrt(5)) = 3, so 5 / 3 + 2 checkpoint slots and a ring of 3, each a
# float and a byte a pixel (6 x 72000 B), 2 depth frames and the 1-channel result (3 x 57600 B):
# 604800 B; and each threshold-map's builtin table, 16488 B (2 x 1025 doubles and the rest of
# its cache): 637776 B, 622.8 KiB.
awk -v k="$kept" 'BEGIN { exit !(k * 1024 >= 622 && k * 1024 <= 623.5) }' && pass ||
  fail "caches: '$kept' MiB, want 622.8 KiB: $(cat pool.txt)"
# The estimate counts the frames the plan keeps and those caches; what was held counts the
# frames and, from each stateful node's first render on, its caches: the estimate, give or take
# a scratch frame, and at least 90% of what the plan has in use at once (caches included).
# Counting the frames alone held 1.8 MiB against 2.3 MiB in use at once.
nd=$(need pool)
awk -v h="$hp" -v e="$est" -v n="$nd" 'BEGIN { exit !(h <= 1.25 * e && h >= 0.75 * e && h >= 0.9 * n) }' && pass ||
  fail "held $hp MiB with the pool, estimate $est MiB of which $kept MiB caches, $nd MiB in use at once"
# The cache alone keeps every frame's plate: five plates of 160x90x26 floats at least.
awk -v p="$hp" -v n="$hn" 'BEGIN { exit !(n >= 5 * 1.42 && p < n / 2) }' && pass ||
  fail "held $hp MiB with the pool, $hn MiB without: the plan did not free"
# The plate (a temporal source, kept one frame) is allocated twice, then reused: 2 plates new
# over 5 frames, against 5 without the pool.
plate_new=$(column pool plate 6); nopool_new=$(column nopool plate 6)
awk -v p="$plate_new" -v n="$nopool_new" 'BEGIN { exit !(p <= 2.5 * 1.43 && n >= 5 * 1.42) }' && pass ||
  fail "plate: $plate_new MiB new with the pool, $nopool_new MiB without"

# A limit just above the frames in use at once fits (the pool gives up its idle buffers), and
# changes no pixel; the frames held then stay under it.
awk -v n="$nd" -v e="$est" 'BEGIN { exit !(n > 0 && n <= e) }' && pass || fail "in use at once $nd MiB, estimate $est MiB"
lim=$(awk -v e="$nd" 'BEGIN { printf "%.0fK", e * 1024 * 1.02 + 64 }')
render tight --mem-limit "$lim"
same tight
ht=$(held tight)
awk -v h="$ht" -v l="${lim%K}" 'BEGIN { exit !(h * 1024 <= l) }' && pass || fail "held $ht MiB under --mem-limit $lim"

# --- above the limit: refused before the first frame ------------------------------------------
below=$(awk -v e="$nd" 'BEGIN { printf "%.0fK", e * 1024 * 0.8 }')
/usr/bin/time -f "%M" -o mem.txt "$NPRFX" run six.json --output-dir over --mem-limit "$below" > over.txt 2> over.err
rc=$?
[ $rc -eq 2 ] && pass || fail "--mem-limit $below: exit $rc, want 2: $(cat over.err)"
grep -qE "six.json: frame 1 needs $num [KM]iB of frames \($num [KM]iB of it the caches nodes keep between frames\) at its peak, at node '[a-z]+' \(its 160x90 frame with [0-9]+ channels?, $num [KM]iB, joins the frames still held\): above the $num [KM]iB memory limit \(--mem-limit\); nothing was rendered" over.err &&
  pass || fail "--mem-limit $below: message: $(cat over.err)"
[ ! -e over ] && pass || fail "a run above --mem-limit wrote $(find over -type f | head -3)"
[ "$(( $(tail -1 mem.txt) / 1024 ))" -lt 256 ] && pass || fail "refusing took $(tail -1 mem.txt) KiB"
# bench-graph and bench refuse the same way.
"$NPRFX" bench-graph "$SRC/samples/bench/bench_six.json" --size 160x90 --frames 2 --mem-limit "$below" > bg.txt 2>&1
rc=$?
[ $rc -eq 2 ] && grep -q "nothing was rendered" bg.txt && pass || fail "bench-graph --mem-limit $below: exit $rc: $(cat bg.txt)"

# --- run --stats ----------------------------------------------------------------------------
grep -qE '^stats: 5 frames$' pool.txt && pass || fail "no 'stats: 5 frames' line: $(cat pool.txt)"
grep -qE '^  node +type +renders +ms/frame +MiB/frame +new MiB$' pool.txt && pass || fail "no stats header: $(cat pool.txt)"
for n in plate:synth noise:coherent-noise grain:threshold-map pencil:blend strokes:gabor-splat hatch:threshold-map look:blend out:write; do
  grep -qE "^  ${n%%:*} +${n#*:} +5 +$num +$num +$num$" pool.txt && pass || fail "no stats row for $n: $(cat pool.txt)"
done
grep -qE "^frames and caches held at most $num [KMG]iB \(estimate $num [KMG]iB, $num [KMG]iB in use at once; memory limit $num [KMG]iB\); peak resident [0-9]+ MiB$" pool.txt &&
  pass || fail "no memory line: $(cat pool.txt)"

# --- bench-graph ----------------------------------------------------------------------------
out=$("$NPRFX" bench-graph "$SRC/samples/bench/bench_six.json" --size 160x90 --frames 3 --threads 1 2>&1)
echo "$out" | grep -qE "bench_six.json 160x90, 3 frames, 1 thread: $num ms/frame, $num frames/s \(first frame $num ms\); compute $num ms, input $num ms, output 0\.0 ms per frame; peak memory [0-9]+ MiB$" &&
  pass || fail "bench-graph form: $out"
# the frames after the first apart (a shot's steady state), consistent with the totals
echo "$out" | grep -qE "^after the first frame: $num ms/frame, $num frames/s; compute $num ms, input $num ms, output 0\.0 ms per frame$" &&
  pass || fail "bench-graph steady-state form: $out"
echo "$out" | awk '
  /frames, 1 thread:/ { match($0, /thread: [0-9.]+/); all = substr($0, RSTART + 8, RLENGTH - 8)
                        match($0, /first frame [0-9.]+/); first = substr($0, RSTART + 12, RLENGTH - 12) }
  /^after the first frame:/ { rest = $5 }
  END { d = all * 3 - (first + rest * 2); exit !(rest > 0 && d < 0.5 && d > -0.5) }' &&
  pass || fail "bench-graph: the steady state does not add up with the first frame to the total: $out"
# --write times the files as output, and writes them; read nodes become synthetic plates.
cat > reads.json <<'JSON'
{"frames": "1-2", "nodes": {
  "plate": {"node": "read", "path": "no/such/plate.####.exr"},
  "grain": {"node": "threshold-map", "inputs": {"pattern": "plate:UV.U", "tone": "plate:diffuse"}, "params": {"mode": "builtin"}},
  "out": {"node": "write", "inputs": {"image": "grain"}, "path": "w/grain.####.exr"}}}
JSON
out=$("$NPRFX" bench-graph reads.json --size 64x32 --frames 2 --write bgw --stats 2>&1)
echo "$out" | grep -qE "output [0-9.]*[1-9][0-9.]* ms per frame" && [ -e bgw/w/grain.0002.exr ] && pass ||
  fail "bench-graph --write: $out"
echo "$out" | grep -qE '^  plate +synth +2 ' && pass || fail "bench-graph did not make the read a synth plate: $out"
# A read of one file (painterly_pam's art map) is a texture, not a plate: it stays a read.
out=$("$NPRFX" bench-graph "$SRC/samples/graphs/painterly_pam.json" --size 64x32 --frames 1 --stats 2>&1)
echo "$out" | grep -qE '^  pam +read +1 ' && pass || fail "bench-graph synthesized the art map: $out"
"$NPRFX" bench-graph reads.json --size big > bad.txt 2>&1; [ $? -eq 2 ] && grep -q "WxH" bad.txt && pass || fail "--size big: $(cat bad.txt)"
"$NPRFX" bench-graph > bad.txt 2>&1; [ $? -eq 2 ] && grep -q "usage" bad.txt && pass || fail "no graph: $(cat bad.txt)"
"$NPRFX" bench-graph reads.json --bogus > bad.txt 2>&1; [ $? -eq 2 ] && grep -q "unexpected argument" bad.txt && pass || fail "--bogus: $(cat bad.txt)"

# --- inputs read in place ----------------------------------------------------------------------
# gabor-splat takes Pref, Z and id out of the synthetic plate: the only frame it allocates is its
# output (640x360, 1 channel: 0.88 MiB); packed copies of the five channels would add 4.4 MiB.
cat > gathered.json <<'JSON'
{"frames": "1", "nodes": {
  "plate": {"node": "synth", "scene": "orbit", "size": "640x360"},
  "strokes": {"node": "gabor-splat", "inputs": {"anchor": "plate:Pref", "depth": "plate:Z", "id": "plate:id"}},
  "out": {"node": "write", "inputs": {"image": "strokes"}, "path": "g/strokes.####.exr"}}}
JSON
out=$("$NPRFX" bench-graph gathered.json --size 640x360 --frames 1 --stats 2>&1)
mib=$(echo "$out" | awk '$1 == "strokes" { print $5 }')
awk -v m="${mib:-99}" 'BEGIN { exit !(m > 0.8 && m < 1.0) }' && pass ||
  fail "gabor-splat allocated ${mib:-?} MiB per frame, not its output's 0.88 (inputs packed?): $out"

echo "$passes passed, $fails failed"
[ $fails -eq 0 ]
