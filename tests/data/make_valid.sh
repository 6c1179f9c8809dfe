#!/usr/bin/env bash
# Writes a corpus of valid image layouts a reader must take faithfully, made here, never copied:
# windows (negative origin, overscan, crop, 1x1), pixel aspect 2, half, tiles, tiled MIP maps,
# multi-part files with parts of other windows, stereo as parts with "view" attributes, deep
# data (which nprfx refuses with advice), and, through the small OpenEXR program
# nprfx-make-exr (tests/data/make_exr.cpp, built with the tests), what oiiotool cannot write:
# exact uint ids beside half and float channels, single-part stereo with the multiView
# attribute in OpenEXR's and Nuke's channel naming, tiled RIPMAP and MIPMAP levels rounded
# down and up, and a multi-part file whose later parts were never written.
# usage: make_valid.sh OUTDIR [NPRFX_MAKE_EXR]   (or $NPRFX_MAKE_EXR; without it those files
# are not made and the script says so)
set -eu
out=$1
make_exr=${2:-${NPRFX_MAKE_EXR:-}}
mkdir -p "$out"
cd "$out"

# A ramp whose every pixel differs, so a shifted or cropped copy cannot pass for the original.
ramp() { echo "--pattern fill:topleft=0,0,0,1:topright=1,0,0.5,1:bottomleft=0,1,0.25,0.5:bottomright=1,1,1,0 $1 4"; }

# One oiiotool run: its start-up dominates. Every file starts from a fresh pattern, so that an
# attribute or origin set for one file cannot leak into the next; the multi-part files are made
# first, since --siappendall takes every image on the stack.
# Multi-part: 'beauty' and 'aov' share a cropped window, 'depth' has the whole frame, 'proxy' is
# a quarter-size preview at the origin (OpenEXR has all parts share one display window).
# Stereo as two parts carrying the "view" attribute: left, the first, is the default view.
# shellcheck disable=SC2046
oiiotool \
    $(ramp 64x48) --crop 32x24+8+4 --attrib oiio:subimagename beauty \
    $(ramp 64x48) --crop 32x24+8+4 --ch R,G,B --chnames N.X,N.Y,N.Z \
    --attrib oiio:subimagename aov \
    $(ramp 64x48) --ch G --chnames Z --attrib oiio:subimagename depth \
    $(ramp 32x24) --ch R,G,B --fullsize 64x48+0+0 --attrib oiio:subimagename proxy \
    --siappendall -o:datatype=float multipart.exr --pop \
    $(ramp 16x12) --ch R,G,B --attrib view left --attrib oiio:subimagename rgba.left \
    --pattern constant:color=0.7,0.8,0.9 16x12 3 --attrib view right \
    --attrib oiio:subimagename rgba.right --siappend -o:datatype=float mv_parts.exr --pop \
    $(ramp 64x48) -o:datatype=float scan_float.exr -o:datatype=half half.exr \
    -o:datatype=half:tile=16x16 tiled.exr -otex:datatype=half tiled_mip.exr --pop \
    $(ramp 64x48) --origin -10-20 -o:datatype=float neg_origin.exr --pop \
    $(ramp 64x48) --crop 32x24+8+4 -o:datatype=float crop.exr --pop \
    $(ramp 64x48) --attrib PixelAspectRatio 2.0 -o:datatype=float aspect2.exr --pop \
    $(ramp 64x48) --cut 1x1+5+7 -o:datatype=float one.exr --pop \
    $(ramp 80x60) --origin -8-6 --fullsize 64x48+0+0 -o:datatype=float overscan.exr --pop \
    --pattern constant:color=0.5,0.25,1,2 8x8 4 --chnames R,G,A,Z --deepen -o:datatype=float deep.exr

if [ -n "$make_exr" ]; then
    "$make_exr" .
else
    echo "make_valid.sh: no nprfx-make-exr given: uint and single-part stereo files not made" >&2
fi
