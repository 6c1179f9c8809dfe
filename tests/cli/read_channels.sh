#!/usr/bin/env bash
# Reading only some channels, and reading by rows (docs/design.md §2.3 "Only the
# channels used"): through `nprfx info --io-test channels|rows`, checked against oiiotool (an
# independent reader) on every storage a block read meets: scanlines of several chunk heights
# (zip 16 rows, piz 32, dwab 256, none 1), tiles whose rows the blocks do not align with, MIP maps,
# a data window at a negative origin, several parts; then a graph over a tiled plate by strips.
#
# usage: bash read_channels.sh NPRFX_BINARY SOURCE_DIR WORK_DIR
set -u
NPRFX=$1; W=$3
rm -rf "$W"; mkdir -p "$W"; cd "$W" || exit 1
passes=0; fails=0
pass() { passes=$((passes+1)); }
fail() { echo "FAIL: $*"; fails=$((fails+1)); }
same() { "$NPRFX" diff "$1" "$2" --fail 0 --hardfail 0 --warn 0 >/dev/null 2>&1; }

# Six channels of distinct ramps and noise, 150x100 (not a multiple of any chunk or tile).
oiiotool --pattern noise:type=uniform:seed=3 150x100 3 --pattern fill:top=0,0.5,1:bottom=1,0.5,0 150x100 3 \
    --chappend --chnames R,G,B,A,Z,W -d half -o scan_zip.exr >/dev/null 2>&1 || fail "oiiotool inputs"
# One oiiotool run per variant: its output settings persist to later outputs of a run.
oiiotool scan_zip.exr --compression piz -o scan_piz.exr >/dev/null 2>&1 || fail "piz"
oiiotool scan_zip.exr --compression dwab -o scan_dwab.exr >/dev/null 2>&1 || fail "dwab"
oiiotool scan_zip.exr --compression none -d float -o scan_none.exr >/dev/null 2>&1 || fail "none"
oiiotool scan_zip.exr -o:datatype=half:tile=16x12 tiled.exr >/dev/null 2>&1 || fail "tiled"
oiiotool scan_zip.exr -otex:datatype=half mip.exr >/dev/null 2>&1 || fail "mip"
oiiotool scan_zip.exr --origin -7-13 -o neg.exr >/dev/null 2>&1 || fail "neg"
oiiotool scan_zip.exr --ch R,G,B --attrib oiio:subimagename rgb scan_zip.exr --ch Z,W \
    --attrib oiio:subimagename zw --siappend -o parts.exr >/dev/null 2>&1 || fail "oiiotool parts"
"$NPRFX" info tiled.exr | grep -q "layout: tiled 16x12" || fail "tiled.exr is not tiled: $("$NPRFX" info tiled.exr)"
"$NPRFX" info mip.exr | grep -q "MIP" || fail "mip.exr has no MIP levels: $("$NPRFX" info mip.exr)"

for f in scan_zip scan_piz scan_dwab scan_none tiled mip neg; do
    # Out of order and with gaps: the plate has them in the order asked, with their file types.
    "$NPRFX" info --io-test channels $f.exr $f.sub.exr W,B,G 2> err.txt || { fail "$f: $(cat err.txt)"; continue; }
    oiiotool $f.exr --ch W,B,G --compression zip -o $f.ref.exr >/dev/null 2>&1 # lossless, unlike dwab
    same $f.sub.exr $f.ref.exr && pass || fail "$f: channels W,B,G differ from oiiotool's"
    # (an EXR stores its channels sorted by name: G B W)
    type=$("$NPRFX" info $f.exr | sed -n 's/^ *R G B A Z W (\(.*\))$/\1/p')
    "$NPRFX" info $f.sub.exr | grep -q "^ *G B W ($type)" && pass ||
        fail "$f: the channels read lost their type ($type): $("$NPRFX" info $f.sub.exr)"
    # Every channel by rows: 1, 7 and 100 rows at a time.
    for rows in 1 7 100; do
        "$NPRFX" info --io-test rows $f.exr $f.r$rows.exr $rows 2> err.txt || { fail "$f rows $rows: $(cat err.txt)"; continue; }
        same $f.r$rows.exr $f.exr && pass || fail "$f: read and written by $rows rows, it differs"
    done
done
"$NPRFX" info neg.r7.exr | grep -q "data window 150x100-7-13" && pass || fail "rows: the window's origin was lost"
# Parts: channels of both parts of the default group, by their names.
"$NPRFX" info --io-test channels parts.exr parts.sub.exr Z,R 2> err.txt || fail "parts: $(cat err.txt)"
oiiotool scan_zip.exr --ch Z,R -o parts.ref.exr >/dev/null 2>&1
same parts.sub.exr parts.ref.exr && pass || fail "parts: channels Z,R differ"
# A channel the file lacks is named, with the part and file.
"$NPRFX" info --io-test channels scan_zip.exr x.exr R,nope 2> err.txt && fail "an absent channel was read"
grep -q "part 0 of 'scan_zip.exr' has no channel 'nope'" err.txt && pass || fail "absent channel: $(cat err.txt)"
# The memory limit counts what is read: 150x100 floats of one channel fit in 64K, of six not.
NPRFX_READ_LIMIT=200K "$NPRFX" info --io-test channels scan_none.exr one.exr R 2> err.txt && pass ||
    fail "one channel under 200K: $(cat err.txt)"
NPRFX_READ_LIMIT=200K "$NPRFX" info --io-test write scan_none.exr all.exr 2> err.txt &&
    fail "six channels were read under 200K"
grep -q "above the 200 KiB memory limit" err.txt && pass || fail "six channels under 200K: $(cat err.txt)"

# A graph over the tiled plate by strips of 5 rows, against the whole frame.
cat > g.json <<'EOF'
{"frames": "1", "nodes": {
 "plate": {"node": "read", "path": "tiled.exr"},
 "m": {"node": "morphology", "inputs": {"image": "plate:R,G,B"}, "params": {"operation": "erode", "radius": 2}},
 "w": {"node": "write", "inputs": {"image": "m"}, "path": "out/m.exr"}
}}
EOF
"$NPRFX" run g.json -q --output-dir whole --strip-rows -1 2> err.txt || fail "whole: $(cat err.txt)"
"$NPRFX" run g.json -q --output-dir s5 --strip-rows 5 2> err.txt || fail "strips: $(cat err.txt)"
same whole/out/m.exr s5/out/m.exr && pass || fail "tiled plate: strips of 5 rows differ from the whole frame"

echo "read_channels: $passes passed, $fails failed"
[ $fails -eq 0 ]
