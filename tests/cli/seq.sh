# Frame sequences (engine/seq.c) driven through `nprfx diff`: frame-list parsing, the ####, @ and
# %04d patterns, frame discovery, missing frames, per-frame difference images.
# usage: bash seq.sh NPRFX SOURCE_DIR WORK_DIR
set -eu
NPRFX=$1
WORK=$3
rm -rf "$WORK"
mkdir -p "$WORK"
cd "$WORK"

fail() {
    echo "FAIL: $*" >&2
    exit 1
}
expect_rc() {
    local want=$1 rc=0
    shift
    "$@" >last.out 2>last.err || rc=$?
    [ "$rc" -eq "$want" ] || { cat last.out last.err >&2; fail "'$*' exited $rc, expected $want"; }
}
# frames_seen: the frame numbers of last.out's per-frame lines, space-separated.
frames_seen() { sed -n 's/^frame \(-*[0-9]*\): .*/\1/p' last.out | tr '\n' ' ' | sed 's/ $//'; }
expect_frames() {
    [ "$(frames_seen)" = "$1" ] || fail "compared frames '$(frames_seen)', expected '$1'"
}

# Frames 1..5, identical except frame 3 (R + 0.5). Copies are cheaper than oiiotool runs.
oiiotool --pattern noise:seed=1 16x16 3 -d float -o base.exr
oiiotool base.exr --addc 0.5,0,0 -o bad.exr
for f in 1 2 3 4 5; do
    cp base.exr "a.000$f.exr"
    cp base.exr "b.000$f.exr"
done
cp bad.exr b.0003.exr
touch a.00003.exr a.3.exr a.0003.exr.bak # near misses that discovery must ignore

# Discovery from A's files, the bad frame found and the worst frame reported.
expect_rc 2 "$NPRFX" diff 'a.####.exr' 'b.####.exr'
expect_frames "1 2 3 4 5"
grep -q "^frame 3: FAILURE" last.out || fail "frame 3 not reported as failing"
grep -q "^worst frame 3:" last.out || fail "worst frame not named"
grep -q 'Comparing "a.0003.exr" and "b.0003.exr"' last.out || fail "worst frame report missing"
grep -qx FAILURE last.out || fail "no overall FAILURE line"
rm a.00003.exr a.3.exr a.0003.exr.bak

# Frame lists: ranges, steps, lists, descending; the three pattern styles.
expect_rc 0 "$NPRFX" diff 'a.####.exr' 'b.####.exr' --frames 1,2,4-5
expect_frames "1 2 4 5"
expect_rc 0 "$NPRFX" diff 'a.%04d.exr' 'b.%04d.exr' --frames 1-5x2 --fail 0.6 --warn 0.6
expect_frames "1 3 5"
expect_rc 2 "$NPRFX" diff 'a.@@@@.exr' 'b.@@@@.exr' --frames 5-1
expect_frames "5 4 3 2 1"
expect_rc 0 "$NPRFX" diff 'a.####.exr' 'b.####.exr' --frames 4
expect_frames "4"
expect_rc 0 "$NPRFX" diff 'a.####.exr' 'b.####.exr' --frames 2 -q
[ "$(cat last.out)" = PASS ] || fail "--quiet sequence printed '$(cat last.out)'"

# A missing frame is a file error naming the file; the other frames are still compared.
expect_rc 4 "$NPRFX" diff 'a.####.exr' 'b.####.exr' --frames 1-7x3
expect_frames "1 4 7"
grep -q "a.0007.exr" last.err || fail "missing frame not named"
grep -q "^frame 7: FILE ERROR" last.out || fail "missing frame not reported"
rm b.0005.exr
expect_rc 4 "$NPRFX" diff 'a.####.exr' 'b.####.exr' --frames 4-5
grep -q "b.0005.exr" last.err || fail "missing frame of B not named"
cp base.exr b.0005.exr

# Widths: '#' is one digit per '#', so a.#.exr finds no frames here; %d is unpadded.
expect_rc 4 "$NPRFX" diff 'a.#.exr' 'b.#.exr'
grep -q "no frames of 'a.#.exr'" last.err || fail "empty sequence not reported"
for f in 1 2 9 10 11; do cp base.exr "u.$f.exr"; cp base.exr "v.$f.exr"; done
expect_rc 0 "$NPRFX" diff 'u.%d.exr' 'v.%d.exr'
expect_frames "1 2 9 10 11"
expect_rc 0 "$NPRFX" diff 'u.#.exr' 'v.#.exr'
expect_frames "1 2 9 10 11" # 10 and 11 overflow a width of one, as printf does

# Negative frames and frames wider than the pattern.
for f in -002 -001 0000 0001 12345; do cp base.exr "n.$f.exr"; cp base.exr "m.$f.exr"; done
expect_rc 0 "$NPRFX" diff 'n.####.exr' 'm.####.exr'
expect_frames "-2 -1 0 1 12345"
expect_rc 0 "$NPRFX" diff 'n.####.exr' 'm.####.exr' --frames=-2--1
expect_frames "-2 -1"

# Per-frame difference images need a pattern in --out.
expect_rc 2 "$NPRFX" diff 'a.####.exr' 'b.####.exr' --out 'd/diff.####.exr' --od
[ -f d/diff.0003.exr ] || fail "difference image for frame 3 missing"
[ ! -e d/diff.0001.exr ] || fail "--od wrote a difference image for an identical frame"
expect_rc 2 "$NPRFX" diff 'a.####.exr' 'b.####.exr' --out single.exr
grep -q "needs a frame pattern" last.err || fail "--out without a pattern accepted"

# A '#' in a directory name is not a frame pattern.
mkdir -p 'take#1'
cp base.exr 'take#1/x.exr'
expect_rc 0 "$NPRFX" diff 'take#1/x.exr' 'take#1/x.exr'
[ -z "$(frames_seen)" ] || fail "a directory '#' was read as a pattern"

# Usage errors: malformed lists, a pattern on one side only, --frames without patterns.
for bad in "" "x" "1-" "1-5x0" "1,,2" "3-1x-1" "1-99999999"; do
    expect_rc 2 "$NPRFX" diff 'a.####.exr' 'b.####.exr' --frames "$bad"
    grep -q "frame range" last.err || fail "bad frame list '$bad' not reported"
done
expect_rc 2 "$NPRFX" diff 'a.####.exr' base.exr
expect_rc 2 "$NPRFX" diff base.exr base.exr --frames 1-3
echo "seq: all checks passed"
