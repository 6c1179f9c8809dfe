#!/usr/bin/env bash
# `nprfx ivs`: writes the stipple node's sequence as the compact file of nprfx/ivs.h (32-byte
# header, 6 bytes a point), deterministic from the seed and prefix-stable in the count; --check
# reads it back, validates it and measures its spacing; corrupt, truncated or foreign files and
# bad options give a clear error and a non-zero exit status. The file the build ships is checked,
# and renders with it equal renders that generate the sequence.
#
# usage: bash stipple_ivs.sh NPRFX_BINARY SOURCE_DIR WORK_DIR
set -u
NPRFX=$1; SRC=$2; W=$3
rm -rf "$W"; mkdir -p "$W"; cd "$W"
passes=0; fails=0
pass() { passes=$((passes+1)); }
fail() { echo "FAIL: $*"; fails=$((fails+1)); }
# expect STATUS TEXT CMD...: CMD exits with STATUS and its output contains TEXT
expect() {
  local want=$1 text=$2; shift 2
  "$@" > out.txt 2>&1; local rc=$?
  if [ "$rc" -eq "$want" ] && grep -qF -- "$text" out.txt; then pass
  else fail "'$*' exited $rc (want $want), output lacks '$text':"; cat out.txt; fi
}
size_of() { wc -c < "$1" | tr -d ' '; }

expect 0 "nprfx ivs -n COUNT" "$NPRFX" ivs --help
expect 0 "--check FILE" "$NPRFX" ivs --help
"$NPRFX" --help | grep -q "ivs" && pass || fail "nprfx --help does not list ivs"

# generate: size, determinism, no temporary file left behind
expect 0 "2000 points" "$NPRFX" ivs -n 2000 -o seq/a.ivs
[ "$(size_of seq/a.ivs)" -eq $((32 + 6 * 2000)) ] && pass || fail "a.ivs is $(size_of seq/a.ivs) bytes, want $((32 + 6 * 2000))"
[ "$(ls seq | wc -l)" -eq 1 ] && pass || fail "the output directory holds more than the file: $(ls seq)"
head -c 8 seq/a.ivs | grep -q NPRFXIVS && pass || fail "no NPRFXIVS magic"
"$NPRFX" ivs -n 2000 -o seq/b.ivs > /dev/null && cmp -s seq/a.ivs seq/b.ivs && pass || fail "two runs differ"
# prefix property: the first 500 points of a 2000-point run are a 500-point run
"$NPRFX" ivs -n 500 -o seq/p.ivs > /dev/null
if cmp -s <(tail -c +33 seq/p.ivs) <(tail -c +33 seq/a.ivs | head -c 3000); then pass
else fail "the 500-point file is not a prefix of the 2000-point file"; fi
# the seed: recorded, and a different sequence
expect 0 "seed 5," "$NPRFX" ivs -n 2000 --seed 5 -o seq/s5.ivs
cmp -s <(tail -c +33 seq/a.ivs) <(tail -c +33 seq/s5.ivs) && fail "seed 5 gives the default sequence" || pass

# check: round trip and the design's spacing bounds
expect 0 "2000 points, seed 20180601" "$NPRFX" ivs --check seq/a.ivs
grep -q "^ok$" out.txt && pass || { fail "--check of a good file did not say ok"; cat out.txt; }
grep -q "n = 64 " out.txt && grep -q "n = 2000 " out.txt && pass || { fail "--check lacks the prefixes"; cat out.txt; }
rs=$(sed -n 's/^r_i \* sqrt(i) for i = [0-9.]*: min \([0-9.]*\) .*max \([0-9.]*\) .*/\1 \2/p' out.txt)
if [ -n "$rs" ] && awk -v a="${rs% *}" -v b="${rs#* }" 'BEGIN { exit !(a >= 0.7 && b <= 0.9) }'; then pass
else fail "r_i*sqrt(i) range '$rs' not within [0.7, 0.9]"; fi
expect 0 "seed 5," "$NPRFX" ivs --check seq/s5.ivs
expect 0 "1 points" "$NPRFX" ivs -n 1 -o seq/one.ivs
expect 0 "too few points" "$NPRFX" ivs --check seq/one.ivs

# corrupt files: a flipped payload byte, truncation, a foreign file, a missing file
cp seq/a.ivs bad.ivs
printf '\377' | dd of=bad.ivs bs=1 seek=1000 conv=notrunc 2> /dev/null
cmp -s bad.ivs seq/a.ivs && fail "could not corrupt the copy" || pass
expect 1 "checksum mismatch" "$NPRFX" ivs --check bad.ivs
grep -q "bad.ivs" out.txt && pass || fail "the error does not name the file"
head -c 5000 seq/a.ivs > short.ivs
expect 1 "truncated" "$NPRFX" ivs --check short.ivs
echo "x,y" > foreign.ivs
expect 1 "not an IVS sequence file" "$NPRFX" ivs --check foreign.ivs
expect 1 "cannot open" "$NPRFX" ivs --check does_not_exist.ivs
cp seq/a.ivs ver.ivs
printf '\011' | dd of=ver.ivs bs=1 seek=8 conv=notrunc 2> /dev/null
expect 1 "version 9" "$NPRFX" ivs --check ver.ivs

# the shipped file: the build writes the first 2^21 points (all a pixel may use) beside the runner (share/nprfx) and
# into the OpenFX bundle; the node reads it, and renders exactly what it renders generating the
# sequence itself ($NPRFX_DATA_DIR empty: no data folder)
BIN=$(cd "$(dirname "$NPRFX")" && pwd)
SHIP="$BIN/share/nprfx/ivs.bin"
expect 0 "2097152 points, seed 20180601" "$NPRFX" ivs --check "$SHIP"
cmp -s "$SHIP" "$BIN/plugins/ofx/nprfx.ofx.bundle/Contents/Resources/ivs.bin" && pass || fail "the OpenFX bundle lacks the shipped ivs.bin"
"$NPRFX" run "$SRC/tests/graphs/stipple.json" --frames 1 --output-dir shipped --quiet && pass || fail "render with the shipped file"
NPRFX_DATA_DIR= "$NPRFX" run "$SRC/tests/graphs/stipple.json" --frames 1 --output-dir generated --quiet && pass || fail "render generating the sequence"
for m in uniform radius multitone 2d; do
  "$NPRFX" diff -q --fail 0 --warn 0 shipped/golden/stipple_$m.0001.exr generated/golden/stipple_$m.0001.exr > /dev/null \
    && pass || fail "stipple $m: the shipped sequence and the generated one render differently"
done
# the runner really looks beside itself: a copy of it with a broken share/nprfx/ivs.bin fails
mkdir -p layout/share/nprfx && cp "$NPRFX" layout/nprfx && cp bad.ivs layout/share/nprfx/ivs.bin
expect 1 "layout/share/nprfx/ivs.bin: ivs: checksum mismatch" layout/nprfx run "$SRC/tests/graphs/stipple.json" --frames 1 --output-dir broken
# a broken data file is an error that names it (a bad install must not pass silently)
mkdir -p data && cp bad.ivs data/ivs.bin
expect 1 "data/ivs.bin: ivs: checksum mismatch" env NPRFX_DATA_DIR="$W/data" "$NPRFX" run "$SRC/tests/graphs/stipple.json" --frames 1 --output-dir broken
cp seq/s5.ivs data/ivs.bin
expect 1 "holds the sequence of seed 5" env NPRFX_DATA_DIR="$W/data" "$NPRFX" run "$SRC/tests/graphs/stipple.json" --frames 1 --output-dir broken

# usage errors
expect 2 "-n must be a whole number" "$NPRFX" ivs -n 0 -o x.ivs
expect 2 "-n must be a whole number" "$NPRFX" ivs -n 12abc -o x.ivs
expect 2 "--seed must be" "$NPRFX" ivs -n 10 --seed -3 -o x.ivs
expect 2 "give -n COUNT and -o FILE" "$NPRFX" ivs -n 10
expect 2 "unexpected argument" "$NPRFX" ivs --bogus
expect 2 "--check takes no other option" "$NPRFX" ivs --check seq/a.ivs -n 5
[ ! -e x.ivs ] && pass || fail "a usage error wrote x.ivs"

echo "$passes passed, $fails failed"
[ $fails -eq 0 ]
