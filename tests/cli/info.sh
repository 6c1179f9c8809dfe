# `nprfx info`: format, size, windows, subimages, compression, channels grouped by layer; exit
# codes 0 / 2 (usage) / 4 (unreadable file).
# usage: bash info.sh NPRFX SOURCE_DIR WORK_DIR
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
# has LINE: last.out holds LINE exactly (leading spaces ignored).
has() {
    sed 's/^ *//' last.out | grep -qxF -- "$1" || { cat last.out >&2; fail "output lacks '$1'"; }
}

# A Blender-like multilayer file: float RGBA, half vector layer, a layer of mixed types.
names=R,G,B,A,ViewLayer.Vector.X,ViewLayer.Vector.Y,ViewLayer.Vector.Z,ViewLayer.Vector.W
names=$names,ViewLayer.Depth.Z,ViewLayer.Mix.V
oiiotool --pattern constant:color=0.5,0.25,0.125,1,0.1,0.2,0.3,0.4,1,2 16x8 10 --chnames "$names" \
    -d float -d ViewLayer.Vector.X=half -d ViewLayer.Vector.Y=half -d ViewLayer.Vector.Z=half \
    -d ViewLayer.Vector.W=half --compression piz -o layers.exr
expect_rc 0 "$NPRFX" info layers.exr
has "layers.exr: openexr 16x8, 10 channels, 1 subimage, compression piz"
has "data window 16x8+0+0, display window 16x8+0+0"
has "R G B A (float)"
has "ViewLayer.Vector: X Y Z W (half)"
has "ViewLayer.Depth: Z (float)"
has "ViewLayer.Mix: V (float)"

# Windows, several files at once, subimages, a non-EXR format.
oiiotool --pattern constant:color=1,0,0 64x48 3 -d float --crop 32x24+8+4 -o crop.exr
# A second part of another data window is skipped by readers but still counted.
oiiotool --pattern constant:color=0.5 64x48 1 --chnames Z -d float -o z.exr
oiiotool crop.exr z.exr --siappend -o parts.exr
oiiotool --pattern constant:color=1,0.5,0 8x8 3 -d uint8 -o small.png
expect_rc 0 "$NPRFX" info crop.exr parts.exr small.png
has "data window 32x24+8+4, display window 64x48+0+0"
has "parts.exr: openexr 32x24, 3 channels, 2 subimages, compression zip"
has "small.png: png 8x8, 3 channels, 1 subimage"
has "R G B (uint8)"

# Each part of a multi-part file, with what a read takes by default.
has "part 0 'subimage00': data window 32x24+8+4, display window 64x48+0+0, read by default"
has "part 1 'subimage01': data window 64x48+0+0, display window 64x48+0+0, read with \"part\""
has "Z (float)"

# Tiles and MIP levels, pixel aspect, deep data (described, though reads refuse it), stereo parts.
oiiotool --pattern constant:color=1,0.5,0 32x16 3 -d half -otex tex.exr \
    --pattern constant:color=1,2 8x8 2 --chnames R,Z -d float --deepen -o deep.exr --pop \
    --pattern constant:color=1,2,3 8x8 3 --attrib PixelAspectRatio 2.0 -o aspect.exr --pop \
    --pattern constant:color=1,2,3 8x8 3 --attrib view left --attrib oiio:subimagename L \
    --pattern constant:color=4,5,6 8x8 3 --attrib view right --attrib oiio:subimagename R \
    --siappend -o stereo.exr
expect_rc 0 "$NPRFX" info tex.exr deep.exr aspect.exr stereo.exr
has "layout: tiled 64x64, 6 MIP levels (reads take level 0)" # maketx tiles 64x64
has "layout: deep (reads refuse it: flatten it first)"
has "layout: pixel aspect 2"
has "views: left (default), right"
has "part 0 'L', view left: data window 8x8+0+0, display window 8x8+0+0, read by default"
has "part 1 'R', view right: data window 8x8+0+0, display window 8x8+0+0, read with \"view\" or \"part\""

# A layer whose channels have different types lists each channel's type.
oiiotool --pattern constant:color=1,2 4x4 2 --chnames P.x,P.y -d float -d P.x=half -o mixed.exr
expect_rc 0 "$NPRFX" info mixed.exr
has "P: x:half y:float"

# Usage and errors.
expect_rc 0 "$NPRFX" info --help
grep -q "usage: nprfx info FILE" last.out || fail "--help prints no usage"
expect_rc 2 "$NPRFX" info
expect_rc 2 "$NPRFX" info --bogus layers.exr
grep -q -- "--bogus" last.err || fail "unknown option not named"
expect_rc 4 "$NPRFX" info missing.exr
grep -q "missing.exr" last.err || fail "error does not name the missing file"
echo "not an image" >junk.exr
expect_rc 4 "$NPRFX" info layers.exr junk.exr
grep -q "junk.exr" last.err || fail "error does not name the unreadable file"
has "ViewLayer.Vector: X Y Z W (half)" # the readable file is still reported
echo "info: all checks passed"
