#!/usr/bin/env bash
# `nprfx bench`: times a node on synthetic plates and reports ms/frame, Mpixel/s, peak memory,
# and what the node counts (stipple: dots drawn; gabor-splat: kernels); bad arguments give a
# usage error. Only the report's form is checked here: speed is measured, never asserted.
#
# usage: bash bench.sh NPRFX_BINARY SOURCE_DIR WORK_DIR
set -u
NPRFX=$1; W=$3
rm -rf "$W"; mkdir -p "$W"; cd "$W"
passes=0; fails=0
pass() { passes=$((passes+1)); }
fail() { echo "FAIL: $*"; fails=$((fails+1)); }
expect() { # STATUS TEXT CMD...
  local want=$1 text=$2; shift 2
  "$@" > out.txt 2>&1; local rc=$?
  if [ "$rc" -eq "$want" ] && grep -qE -- "$text" out.txt; then pass
  else fail "'$*' exited $rc (want $want), output lacks /$text/:"; cat out.txt; fi
}

for m in uniform radius multitone; do
  expect 0 "^stipple 160x90, 2 frames, 1 thread: [0-9.]+ ms/frame \(best [0-9.]+; CPU [0-9.]+\), [0-9.]+ Mpixel/s, peak memory [0-9]+ MiB$" \
    "$NPRFX" bench stipple --size 160x90 --frames 2 --threads 1 --connect uv=UV.U,UV.V --connect id=id --set mode=$m
  n=$(sed -n 's/^stipple: \([0-9]*\) stipples\/frame, [0-9.]* M stipples\/s$/\1/p' out.txt)
  [ -n "$n" ] && [ "$n" -gt 50 ] && pass || { fail "$m: no plausible 'stipples/frame' line"; cat out.txt; }
done
expect 0 "^gabor-splat: [0-9]+ kernels/frame" "$NPRFX" bench gabor-splat --size 96x64 --frames 1
expect 0 "ms/frame" "$NPRFX" bench blend --size 500x500 --frames 1
# blend reads base and layer (RGBA each) and writes RGBA: 12 floats a pixel, 12 MB a frame
grep -qE "^memory floor: [0-9.]+ ms/frame \(12 MB of frames read and written at [0-9.]+ GB/s memcpy\); the node takes [0-9.]+x that$" out.txt \
  && pass || { fail "blend: no memory floor line"; cat out.txt; }
! grep -q "^blend:" out.txt && pass || fail "blend reports a count it does not make"
# warp's offset names no AOV and takes 2 channels: bench connects the plate's motion to it.
expect 0 "^warp 64x36, 1 frame" "$NPRFX" bench warp --size 64x36 --frames 1
expect 2 "unknown node 'nope'" "$NPRFX" bench nope
expect 2 "--size must be WxH" "$NPRFX" bench blend --size big
expect 2 "unexpected argument" "$NPRFX" bench blend --bogus
expect 2 "unknown param|no param" "$NPRFX" bench stipple --size 64x64 --frames 1 --set nothing=1
expect 0 "stipples/frame and per second|that count per frame" "$NPRFX" bench --help

echo "$passes passed, $fails failed"
[ $fails -eq 0 ]
