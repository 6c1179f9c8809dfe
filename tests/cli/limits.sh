#!/usr/bin/env bash
# Frames larger than the memory limit are refused up front, naming the size and the limit
# (nprfx synth --size, a graph's synth node and "format", a graph whose
# planned peak is above it, with NPRFX_READ_LIMIT followed and --mem-limit overriding it. Each
# refusal must come fast and in little memory: nothing is allocated first.
set -u
NPRFX=$1
WORK=$3
rm -rf "$WORK"
mkdir -p "$WORK"
cd "$WORK" || exit 1
fail=0
bad() {
    echo "FAIL: $*"
    fail=1
}
# expect_refused STATUS PATTERN CMD...: exit STATUS, stderr matching PATTERN, < 256 MiB.
expect_refused() {
    local want=$1 pattern=$2
    shift 2
    /usr/bin/time -f "%M" -o mem.txt "$@" >out.txt 2>err.txt
    local rc=$?
    [ "$rc" -eq "$want" ] || bad "$*: exit $rc, expected $want: $(cat err.txt)"
    grep -qE -- "$pattern" err.txt || bad "$*: message: $(cat err.txt)"
    local kib
    kib=$(tail -1 mem.txt)
    [ "$((kib / 1024))" -lt 256 ] || bad "$*: $((kib / 1024)) MiB before refusing"
}
expect_refused 2 "nprfx synth: --size 16384x16384 with 26 channels needs 26(\.0)? GiB, above the .* memory limit \(half the physical memory; --mem-limit or NPRFX_READ_LIMIT sets it\)" \
    "$NPRFX" synth orbit --size 16384x16384 -o big.exr
[ -e big.exr ] && bad "synth wrote big.exr"
# The limit follows NPRFX_READ_LIMIT both ways.
expect_refused 2 "--size 64x64 with 26 channels needs 416 KiB, above the 100 KiB memory limit \(NPRFX_READ_LIMIT\)" \
    env NPRFX_READ_LIMIT=100K "$NPRFX" synth orbit --size 64x64 -o small.exr
NPRFX_READ_LIMIT=1M "$NPRFX" synth orbit --size 64x64 -o small.exr >/dev/null 2>err.txt || bad "64x64 under 1M: $(cat err.txt)"

cat >synth.json <<'JSON'
{"frames": "1", "nodes": {
  "plate": {"node": "synth", "scene": "orbit", "size": "16384x16384"},
  "out": {"node": "write", "inputs": {"image": "plate"}, "path": "out.####.exr"}}}
JSON
# (the plan refuses it: a graph's synth makes only what its readers take, here all 26 channels)
expect_refused 2 "synth.json: frame 1 needs 26(\.0)? GiB of frames at its peak, at node 'plate' \(its 16384x16384 frame with 26 channels, 26(\.0)? GiB, .*above the .* memory limit.*nothing was rendered" \
    "$NPRFX" run synth.json
cat >format.json <<'JSON'
{"frames": "1", "format": "60000x60000", "nodes": {
  "paper": {"node": "paper"},
  "out": {"node": "write", "inputs": {"image": "paper"}, "path": "out.####.exr"}}}
JSON
expect_refused 2 "format.json: \"format\" 60000x60000 with 1 channel needs 13.4 GiB, above the" \
    "$NPRFX" run format.json
# A graph whose frames need more than the limit fails before its first frame (the plan's estimate),
# naming the node and the sizes: paper's 2000x2000 RGBA frame under 20 MiB (the format
# alone fits). Nothing is written.
sed 's/60000x60000/2000x2000/' format.json >format2.json
# (paper keeps its last window between frames, so the frame counts twice: once as the output,
# once as the node's cache)
expect_refused 2 "format2.json: frame 1 needs 122 MiB of frames \(61.0 MiB of it the caches nodes keep between frames\) at its peak, at node 'paper' \(its 2000x2000 frame with 4 channels, 61.0 MiB, joins the frames still held\): above the 20 MiB memory limit \(NPRFX_READ_LIMIT\); nothing was rendered" \
    env NPRFX_READ_LIMIT=20M "$NPRFX" run format2.json
[ -e out.0001.exr ] && bad "format2.json wrote a frame above the limit"
# run --check refuses it too (the plan reads no pixel and allocates no frame), and passes it under
# a limit it fits.
expect_refused 2 "format2.json: frame 1 needs 122 MiB of frames \(61.0 MiB of it the caches nodes keep between frames\) at its peak, at node 'paper'" \
    env NPRFX_READ_LIMIT=20M "$NPRFX" run --check format2.json
NPRFX_READ_LIMIT=160M "$NPRFX" run --check format2.json >out.txt 2>err.txt ||
    bad "run --check under 160M: $(cat err.txt)"
grep -q "format2.json: ok: 1 frame would write" out.txt || bad "run --check: $(cat out.txt)"
[ -e out.0001.exr ] && bad "run --check wrote a frame"
# --mem-limit overrides NPRFX_READ_LIMIT, both ways, and names itself.
expect_refused 2 "at node 'paper' .* above the 20 MiB memory limit \(--mem-limit\); nothing was rendered" \
    env NPRFX_READ_LIMIT=8G "$NPRFX" run format2.json --mem-limit 20M
[ -e out.0001.exr ] && bad "format2.json wrote a frame above --mem-limit"
NPRFX_READ_LIMIT=20M "$NPRFX" run format2.json --mem-limit 160M -q 2>err.txt || bad "--mem-limit 160M over NPRFX_READ_LIMIT=20M: $(cat err.txt)"
[ -e out.0001.exr ] || bad "format2.json under --mem-limit 160M wrote nothing"
expect_refused 2 "--mem-limit 'lots' is not a size" "$NPRFX" run format2.json --mem-limit lots
expect_refused 2 "nprfx bench: frame 1 needs 128 KiB of frames at its peak, at node 'bench' \(its 64x64 frame with 4 channels, 64 KiB, joins the frames still held\): above the 100 KiB memory limit \(--mem-limit\); nothing was rendered" \
    "$NPRFX" bench blend --size 64x64 --frames 1 --mem-limit 100K
[ $fail -eq 0 ] && echo "limits: all checks passed"
exit $fail
