# The image I/O library (io/, libnprfx-io) through `nprfx info --io-test`, with oiiotool/iinfo as
# independent readers: round trips, half/compression, windows, atomic writes, previews, colour.
# usage: bash io.sh NPRFX SOURCE_DIR WORK_DIR
set -eu
NPRFX=$1
WORK=$3
rm -rf "$WORK"
mkdir -p "$WORK"
cd "$WORK"
unset OCIO

fail() {
    echo "FAIL: $*" >&2
    exit 1
}
# expect_rc CODE CMD...: run CMD (output to last.out/last.err) and check its exit status.
expect_rc() {
    local want=$1 rc=0
    shift
    "$@" >last.out 2>last.err || rc=$?
    [ "$rc" -eq "$want" ] || { cat last.out last.err >&2; fail "'$*' exited $rc, expected $want"; }
}
# stats FILE: the per-channel averages oiiotool reports (alpha left unassociated for PNGs).
stats() {
    oiiotool --iconfig oiio:UnassociatedAlpha 1 "$1" --printstats | sed -n 's/.*Stats Avg: //p'
}
# near "A B C" "X Y Z" TOL: element-wise |a - x| <= TOL.
near() {
    awk -v a="$1" -v b="$2" -v t="$3" 'BEGIN { n = split(a, x, " "); m = split(b, y, " ");
        if (n < m) exit 1;
        for (i = 1; i <= m; i++) { d = x[i] - y[i]; if (d < 0) d = -d; if (d > t) exit 1 } }' ||
        fail "values '$1' differ from '$2' by more than $3"
}
no_temp_files() {
    local left
    left=$(find . -name '.*.tmp-*')
    [ -z "$left" ] || fail "temporary files left: $left"
}

# The inputs, in two oiiotool runs (process start-up dominates these tests).
oiiotool --pattern constant:color=0.5,0.25,0.125,1 64x48 4 -d float -o a.exr \
    --dup --crop 32x24+8+8 -o crop.exr --pop \
    --dup --ch R -o grey.exr --pop \
    --dup --ch R,G -o rg.exr --pop \
    --pattern noise:min=-1:max=2 64x48 3 \
    --chnames ViewLayer.Vector.X,ViewLayer.Vector.Y,ViewLayer.Vector.Z -o vec.exr \
    --chappend -o multi.exr \
    --pattern constant:color=2,-1,0.5 4x4 3 -o clamp.exr \
    --pattern constant:color=0.18,0.03125,0.5,0.5 8x8 4 -o pre.exr \
    --pattern constant:color=1.6298145e-9 4x4 1 --chnames id -d uint32 -o id.exr
oiiotool a.exr vec.exr --siappend -o parts.exr

# Round trip: every channel bit-exact, parent directories created, zip by default.
expect_rc 0 "$NPRFX" info --io-test write multi.exr out/deep/dir/w.exr
[ -f out/deep/dir/w.exr ] || fail "write did not create out/deep/dir/w.exr"
expect_rc 0 "$NPRFX" diff multi.exr out/deep/dir/w.exr --fail 0 --warn 0
iinfo -v out/deep/dir/w.exr >last.out
grep -q 'compression: "zip"' last.out || fail "default compression is not zip"
grep -q 'ViewLayer.Vector.Z' last.out || fail "channel names not kept"
expect_rc 0 idiff -fail 0 -warn 0 multi.exr out/deep/dir/w.exr

# Half and another compression, checked by iinfo; values within half precision.
expect_rc 0 "$NPRFX" info --io-test write multi.exr h.exr --half --compression piz
iinfo -v h.exr >last.out
grep -q 'half openexr' last.out || fail "--half did not store half floats"
grep -q 'compression: "piz"' last.out || fail "compression piz not written"
expect_rc 0 "$NPRFX" diff multi.exr h.exr --fail 2e-3 --warn 2e-3
expect_rc 2 "$NPRFX" diff multi.exr h.exr --fail 1e-7

# Data and display windows survive a round trip.
expect_rc 0 "$NPRFX" info --io-test write crop.exr crop2.exr
iinfo -v crop2.exr >last.out
grep -q '32 x   24' last.out || fail "cropped data window size lost"
grep -q 'full/display size: 64 x 48' last.out || fail "display window lost"
grep -q 'pixel data origin: x=8, y=8' last.out || fail "data window origin lost"

# Multi-part files: parts concatenated, repeated names prefixed with the part's name.
expect_rc 0 "$NPRFX" info --io-test channel parts.exr ViewLayer.Vector.Y
[ "$(cat last.out)" = 5 ] || fail "channel lookup in a multi-part file gave $(cat last.out)"
expect_rc 0 "$NPRFX" info --io-test channel parts.exr nothing
[ "$(cat last.out)" = -1 ] || fail "absent channel not -1"
expect_rc 0 "$NPRFX" info --io-test view multi.exr 1 2
grep -q 'channels 2 pixel_stride 7 row_stride 448 first 0.25' last.out ||
    fail "plate view: $(cat last.out)"
expect_rc 0 "$NPRFX" info --io-test view multi.exr 6 2
grep -q absent last.out || fail "out-of-range plate view not absent"

# EXR UINT channels (object ids, id.exr holds 7) are read as integer values, not normalised.
expect_rc 0 "$NPRFX" info --io-test view id.exr 0 1
grep -q 'first 7$' last.out || fail "uint id channel read as $(cat last.out)"

# Atomic writes: a failed write leaves the old file and no temporary behind.
cp a.exr keep.exr
expect_rc 4 "$NPRFX" info --io-test write vec.exr keep.exr --compression bogus
grep -q "keep.exr" last.err || fail "error does not name the file"
grep -q "bogus" last.err || fail "error does not name the compression"
expect_rc 0 "$NPRFX" diff a.exr keep.exr
mkdir -p isdir.exr
expect_rc 4 "$NPRFX" info --io-test write a.exr isdir.exr
grep -q "isdir.exr" last.err || fail "rename failure does not name the file"
no_temp_files

# Previews: sRGB transfer without a config, raw, channel counts, alpha linear.
expect_rc 0 "$NPRFX" info --io-test preview a.exr p.png
iinfo p.png | grep -q '4 channel, uint8 png' || fail "preview is not an 8-bit RGBA png"
near "$(stats p.png)" "188 137 99 255" 1
expect_rc 0 "$NPRFX" info --io-test preview a.exr raw.png --raw
near "$(stats raw.png)" "127.5 64 32 255" 1
expect_rc 0 "$NPRFX" info --io-test preview grey.exr grey.png
iinfo grey.png | grep -q '1 channel, uint8 png' || fail "1-channel preview is not grey"
near "$(stats grey.png)" "188" 1
expect_rc 0 "$NPRFX" info --io-test preview rg.exr rg.png
iinfo rg.png | grep -q '3 channel, uint8 png' || fail "2-channel preview is not RGB"
near "$(stats rg.png)" "188 137 0" 1
expect_rc 0 "$NPRFX" info --io-test preview clamp.exr clamp.png
near "$(stats clamp.png)" "255 0 188" 1

# OCIO: a tiny config whose view is a square root; premultiplied colour is un-premultiplied
# (PNG alpha is unassociated), alpha stays linear. The config also comes from $OCIO.
cat >test.ocio <<'EOF'
ocio_profile_version: 2
roles:
  default: lin
  scene_linear: lin
displays:
  test:
    - !<View> {name: sqrt, colorspace: sqrt}
    - !<View> {name: identity, colorspace: lin}
colorspaces:
  - !<ColorSpace>
    name: lin
  - !<ColorSpace>
    name: sqrt
    from_scene_reference: !<ExponentTransform> {value: [0.5, 0.5, 0.5, 1]}
EOF
expect_rc 0 "$NPRFX" info --io-test preview pre.exr ocio.png --ocio test.ocio
near "$(stats ocio.png)" "153 63.75 255 127.5" 1
expect_rc 0 "$NPRFX" info --io-test preview pre.exr ocio2.png --ocio test.ocio --view identity
near "$(stats ocio2.png)" "91.8 15.9 255 127.5" 1
OCIO=test.ocio expect_rc 0 "$NPRFX" info --io-test preview pre.exr env.png
near "$(stats env.png)" "153 63.75 255 127.5" 1
expect_rc 4 "$NPRFX" info --io-test preview pre.exr bad.png --ocio test.ocio --colorspace nope
grep -q "nope" last.err || fail "preview error does not name the colour space"
[ ! -e bad.png ] || fail "failed preview left a file"
expect_rc 4 "$NPRFX" info --io-test preview pre.exr bad.png --ocio missing.ocio
grep -q "missing.ocio" last.err || fail "config error does not name the config"

# Colour conversion: built-in linear/srgb round trip, OCIO names, unknown names.
expect_rc 0 "$NPRFX" info --io-test convert a.exr s.exr linear srgb
near "$(stats s.exr)" "0.735357 0.537099 0.388573 1" 1e-5
expect_rc 0 "$NPRFX" info --io-test convert s.exr l.exr srgb linear
expect_rc 0 "$NPRFX" diff a.exr l.exr --fail 1e-6
expect_rc 0 "$NPRFX" info --io-test convert pre.exr sq.exr lin sqrt --ocio test.ocio
near "$(stats sq.exr)" "0.424264 0.176777 0.707107 0.5" 1e-5
expect_rc 4 "$NPRFX" info --io-test convert a.exr x.exr linear acescg
grep -q "acescg" last.err || fail "unknown colour space not named"
expect_rc 4 "$NPRFX" info --io-test convert a.exr x.exr lin nope --ocio test.ocio
grep -q "nope" last.err || fail "unknown OCIO colour space not named"
no_temp_files
echo "io: all checks passed"
