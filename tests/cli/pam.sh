# `nprfx pam`: build a PAM from the shipped samples (same bytes on 1 and 2 threads), `info` on it,
# the samples generator matching samples/pam, and the bad-input errors, each naming the file.
# usage: bash pam.sh NPRFX SOURCE_DIR WORK_DIR
set -eu
NPRFX=$1
SRC=$2
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
err_has() {
    grep -qF -- "$1" last.err || { cat last.err >&2; fail "stderr lacks '$1'"; }
}
out_has() {
    grep -qF -- "$1" last.out || { cat last.out >&2; fail "stdout lacks '$1'"; }
}

S=$SRC/samples/pam
# Small and quick: 128-pixel maps from the shipped 256-pixel samples.
build() {
    "$NPRFX" pam build --sample "$S/strokes_1.png" --sample "$S/strokes_2.png" \
        --sample "$S/strokes_3.png" --size 128 --patch 16 --overlap 3 "$@"
}
expect_rc 0 build -o t1.pam.exr --threads 1
out_has "wrote t1.pam.exr:"
expect_rc 0 build -o t2.pam.exr --threads 2
# Same pixels to the bit and the same attributes (the files differ only in OIIO's DateTime).
expect_rc 0 "$NPRFX" diff t1.pam.exr t2.pam.exr --fail 0 --failpercent 0 --hardfail 0
out_has "Max error  = 0"
for f in t1 t2; do oiiotool --info -v $f.pam.exr | grep nprfx: >$f.attrs; done
cmp -s t1.attrs t2.attrs || fail "1 and 2 threads wrote different attributes"

expect_rc 0 "$NPRFX" pam info t1.pam.exr "$S/strokes.pam.exr" # the shipped PAM is valid too
out_has "t1.pam.exr: PAM version 1"
out_has "strokes.pam.exr: PAM version 1"
[ "$(grep -c "^keys: 0,[0-9]*,[0-9]*$" last.out)" -eq 2 ] || { cat last.out >&2; fail "keys line"; }
count=$(sed -n 's/^t1.pam.exr: PAM version 1, \([0-9]*\) maps of 128x128.*/\1/p' last.out)
[ -n "$count" ] && [ "$count" -ge 3 ] || fail "count '$count'"
[ "$(grep -c '^ *[0-9][0-9]*  key ' last.out)" -eq 6 ] || fail "three key rows per file expected"
# The header as any EXR reader sees it.
oiiotool --info -v t1.pam.exr >hdr.txt
grep -q 'nprfx:pam: 1' hdr.txt || fail "no nprfx:pam attribute"
grep -q "nprfx:pamCount: $count" hdr.txt || fail "nprfx:pamCount"
grep -q 'nprfx:pamMeanY: "' hdr.txt || fail "nprfx:pamMeanY"
# The generator still paints the shipped samples.
expect_rc 0 "$NPRFX" pam samples -o gen --size 256
for i in 1 2 3 4; do
    # the pixels (a PNG's bytes follow its compression level)
    "$NPRFX" diff "gen/strokes_$i.png" "$S/strokes_$i.png" --fail 0 --warn 0 -q >/dev/null 2>&1 ||
        fail "strokes_$i.png differs from samples/pam"
done

# Bad input, each naming the file.
oiiotool --pattern constant:color=0.2,0.3,0.4 128x128 3 -d uint8 -o small.png
expect_rc 1 "$NPRFX" pam build --sample "$S/strokes_1.png" --sample small.png -o x.pam.exr
err_has "'small.png' is 128x128 but '$S/strokes_1.png' is 256x256"
oiiotool --pattern constant:color=0.2,0.3,0.4 20x20 3 -d uint8 -o tiny.png
expect_rc 1 "$NPRFX" pam build --sample tiny.png --sample tiny.png -o x.pam.exr
err_has "'tiny.png' (20x20) is smaller than a patch with its overlap (80x80)"
echo "not an image" >bad.png
expect_rc 1 "$NPRFX" pam build --sample "$S/strokes_1.png" --sample bad.png -o x.pam.exr
err_has "bad.png"
[ ! -e x.pam.exr ] || fail "a failed build left a file"
expect_rc 2 "$NPRFX" pam build --sample "$S/strokes_1.png" -o x.pam.exr
expect_rc 2 "$NPRFX" pam build --sample "$S/strokes_1.png" --sample "$S/strokes_2.png" -o x.png

# Files that are not PAMs, checked in one run (each message names its file): no nprfx:pam, a
# width that is not a multiple of the height, one map, attributes that disagree with the pixels,
# a truncated file.
oiiotool --pattern constant:color=0.5,0.5,0.5 256x128 3 -d half -o plain.exr \
    --attrib:type=int nprfx:pam 1 --attrib:type=int nprfx:pamCount 1 --cut 128x128 -o one.exr \
    --pattern constant:color=0.5,0.5,0.5 300x128 3 -d half --attrib:type=int nprfx:pam 1 -o odd.exr
oiiotool t1.pam.exr --attrib:type=int nprfx:pamCount 99 -o wrongcount.exr \
    --attrib:type=int nprfx:pamCount "$count" \
    --attrib:type=string nprfx:pamMeanY "$(yes 0.9 | head -n "$count" | paste -sd,)" -o wrongmean.exr
head -c 2000 t1.pam.exr >cut.exr
expect_rc 1 "$NPRFX" pam info plain.exr odd.exr one.exr wrongcount.exr wrongmean.exr cut.exr t1.pam.exr
err_has "'plain.exr' is not a PAM: it has no nprfx:pam attribute"
err_has "'odd.exr': pam: a PAM's width is a whole number of square maps, but 300x128 is not a multiple of its height"
err_has "'one.exr': pam: 128x128 holds 1 map(s); a PAM holds 2 to"
err_has "'wrongcount.exr': nprfx:pamCount is 99 but the image holds $count maps"
err_has "'wrongmean.exr': nprfx:pamMeanY of map 0 is 0.9 but its pixels give"
err_has "cut.exr"
out_has "t1.pam.exr: PAM version 1" # the good file among them is still described
expect_rc 2 "$NPRFX" pam info
expect_rc 2 "$NPRFX" pam frobnicate
echo "pam: ok"
