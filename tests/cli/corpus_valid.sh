# Valid layouts read faithfully: tests/data/make_valid.sh writes a corpus (windows with negative
# origins, overscan and crops, 1x1, pixel aspect 2, half, tiles, MIP maps, multi-part files,
# stereo as parts and as one part in OpenEXR's and Nuke's naming, exact uint ids beside half and
# float, RIPMAP and MIPMAP levels rounded down and up, a tiled file whose "type" attribute says
# scanline, a multi-part file whose later parts were never written), every file goes through a
# read->write
# graph, and OpenImageIO, an independent reader, checks the copy against the part or view read
# (a tiled file's level 0): windows, channel names and types, pixel aspect,
# values (idiff) and, where the types are the file's own, the pixel data's hash (which sees uint
# ids exactly, those above 2^24 too). Then the refusals and warnings: deep data, a missing part or
# view, inputs at different origins.
# usage: bash corpus_valid.sh NPRFX SOURCE_DIR WORK_DIR  (NPRFX_MAKE_EXR: the nprfx-make-exr program)
set -eu
NPRFX=$1
SRC=$2
WORK=$3
rm -rf "$WORK"
mkdir -p "$WORK"
cd "$WORK"
unset OCIO

fail() {
    echo "FAIL: $*" >&2
    exit 1
}
[ -n "${NPRFX_MAKE_EXR:-}" ] && [ -x "$NPRFX_MAKE_EXR" ] ||
    fail "NPRFX_MAKE_EXR does not name the nprfx-make-exr program (tests/CMakeLists.txt sets it)"
bash "$SRC/tests/data/make_valid.sh" in "$NPRFX_MAKE_EXR"

fail_log() { # MESSAGE: the run's messages, then fail
    cat last.err >&2
    fail "$*"
}
# Start-up dominates every OIIO program here, so each tool runs once over all files: one graph
# copies every case, one `nprfx run` takes every graph that must fail, one iinfo, one hash run.

# The copies: case name, file, part, view, channels the write takes ("-": none).
cases="scan_float scan_float.exr - - -
half half.exr - - -
neg_origin neg_origin.exr - - -
crop crop.exr - - -
aspect2 aspect2.exr - - -
one one.exr - - -
overscan overscan.exr - - -
tiled tiled.exr - - -
tiled_mip tiled_mip.exr - - -
rip_down rip_down.exr - - -
rip_up rip_up.exr - - -
mip_up mip_up.exr - - -
tiled_typed tiled_typed_scanline.exr - - -
unf_default unfinished.exr - - -
unf_aov unfinished.exr aov - -
uint_mixed uint_mixed.exr - - -
uint_big uint_big.exr - - -
uint_sub uint_mixed.exr - - B,id
mp_default multipart.exr - - -
mp_depth multipart.exr depth - -
mp_2 multipart.exr 2 - -
mp_proxy multipart.exr proxy - -
mp_want multipart.exr - - Z
mvp_default mv_parts.exr - - -
mvp_right mv_parts.exr - right -
mve_left mv_exr.exr - - -
mve_right mv_exr.exr - right -
mvn_left mv_nuke.exr - - -
mvn_right mv_nuke.exr - right -"
{
    echo '{"frames": "1", "nodes": {'
    while read -r name file part view sel; do
        printf '  "r_%s": {"node": "read", "path": "in/%s"' "$name" "$file"
        [ "$part" = - ] || printf ', "part": "%s"' "$part"
        [ "$view" = - ] || printf ', "view": "%s"' "$view"
        printf '},\n  "w_%s": {"node": "write", "inputs": {"image": "r_%s%s"}, "path": "out/%s.exr"},\n' \
            "$name" "$name" "$([ "$sel" = - ] || echo ":$sel")" "$name"
    done <<<"$cases"
    # Display window and pixel aspect through a processing node: the output lies on its input.
    echo '  "r_node": {"node": "read", "path": "in/crop.exr"},'
    echo '  "mix": {"node": "blend", "inputs": {"base": "r_node:R,G,B", "layer": "r_node:R,G,B"}},'
    echo '  "w_node": {"node": "write", "inputs": {"image": "mix"}, "path": "out/node.exr"}}}'
} >copy.json
rc=0
"$NPRFX" run copy.json >last.out 2>last.err || rc=$?
[ "$rc" -eq 0 ] || fail_log "copying the corpus failed"
cp last.err copy.err

# The references, as OIIO reads the part or view: a MIP map's level 0, parts, renamed views.
mkdir -p ref
oiiotool in/tiled_mip.exr --unmip -o ref/tiled_mip.exr \
    in/rip_down.exr --unmip -o ref/rip_down.exr in/rip_up.exr --unmip -o ref/rip_up.exr \
    in/mip_up.exr --unmip -o ref/mip_up.exr \
    in/unfinished.exr --subimage 0 in/unfinished.exr --subimage 1 --chappend -o ref/unf_default.exr \
    in/unfinished.exr --subimage 1 -o ref/unf_aov.exr \
    in/multipart.exr --subimage 0 in/multipart.exr --subimage 1 --chappend -o ref/mp_default.exr \
    in/multipart.exr --subimage 2 -o ref/mp_depth.exr \
    in/multipart.exr --subimage 3 -o ref/mp_proxy.exr \
    in/mv_parts.exr --subimage 0 -o ref/mvp_default.exr \
    in/mv_parts.exr --subimage 1 -o ref/mvp_right.exr \
    in/mv_exr.exr --ch R,G,B,diffuse.R -o ref/mv_left.exr \
    in/mv_exr.exr --ch R=right.R,G=right.G,B=right.B,diffuse.R=diffuse.right.R -o ref/mv_right.exr
for f in scan_float half neg_origin crop aspect2 one overscan tiled uint_mixed uint_big; do
    ln -s "../in/$f.exr" "ref/$f.exr"
done
ln -s ../in/tiled_typed_scanline.exr ref/tiled_typed.exr
ln -s mp_depth.exr ref/mp_2.exr
ln -s mp_depth.exr ref/mp_want.exr
same_layout="scan_float half neg_origin crop aspect2 one overscan tiled tiled_mip rip_down rip_up
    mip_up tiled_typed unf_default unf_aov uint_mixed uint_big mp_default mp_depth mp_2 mp_proxy mp_want mvp_default mvp_right"

# What must survive, as iinfo -v prints it: size, channel count and types, channel names (with
# per-channel types when mixed), data origin, display window, pixel aspect; one line per file.
iinfo -v ref/*.exr out/*.exr | awk '
    /^[^ ]/ { if (f != "") print f "\t" l; split($0, a, " : "); f = a[1]; sub(/ +$/, "", f); l = a[2]; next }
    /^ *(channel list|pixel data origin|full\/display size|full\/display origin|PixelAspectRatio):/ {
        sub(/^ +/, ""); l = l " | " $0 }
    END { print f "\t" l }' >layouts.txt
oiiotool --hash ref/*.exr out/*.exr | awk '
    /^[^ ]/ { split($0, a, " : "); f = a[1]; sub(/ +$/, "", f) }
    /SHA-1:/ { print f "\t" $2 }' >hashes.txt
field() { awk -F '\t' -v f="$2" '$1 == f { print $2 }' "$1"; }

# Every copy keeps its reference's layout and, bit for bit, its pixel data (the hash sees the
# native types, so uint ids are compared exactly).
for c in $same_layout; do
    [ -f "out/$c.exr" ] || fail "out/$c.exr was not written"
    want=$(field layouts.txt "ref/$c.exr")
    got=$(field layouts.txt "out/$c.exr")
    [ -n "$want" ] && [ "$want" = "$got" ] || fail "out/$c.exr has layout
  $got
instead of
  $want"
    [ "$(field hashes.txt "ref/$c.exr")" = "$(field hashes.txt "out/$c.exr")" ] ||
        fail "out/$c.exr holds other pixel data than ref/$c.exr"
done
# What those comparisons rest on, spelled out.
case "$(field layouts.txt out/aspect2.exr)" in *"PixelAspectRatio: 2"*) ;; *) fail "pixel aspect 2 lost" ;; esac
case "$(field layouts.txt out/overscan.exr)" in *"origin: x=-8, y=-6"*) ;; *) fail "overscan lost" ;; esac
case "$(field layouts.txt out/uint_mixed.exr)" in *"id (uint)"*) ;; *) fail "uint ids not kept as uint" ;; esac
# A plate of which the graph reads some channels is trimmed to them (the frame-buffer pool): the
# file types follow the channels they belong to.
case "$(field layouts.txt out/uint_sub.exr)" in
*"channel list: B (half), id (uint) | pixel data origin: x=-3, y=2"*) ;;
*) fail "a trimmed plate lost its channels' types: $(field layouts.txt out/uint_sub.exr)" ;;
esac
case "$(field layouts.txt out/node.exr)" in *"origin: x=8, y=4 | full/display size: 64 x 48"*) ;;
*) fail "a node's output lost the data or display window: $(field layouts.txt out/node.exr)" ;; esac
iinfo -v out/tiled_mip.exr | grep -q MIP && fail "a copy of a MIP map should be level 0 alone"
# The rip and MIP maps are what they say (levels; rounded up), and their copies level 0 alone:
# each level adds 0.125 (lx + 2 ly) to level 0's values, so another level would fail the hashes.
for f in rip_down rip_up mip_up; do
    iinfo -v "in/$f.exr" | grep -q 'MIP-map levels' || fail "in/$f.exr has no levels"
    iinfo -v "out/$f.exr" | grep -q MIP && fail "a copy of $f.exr should be level 0 alone"
done
iinfo -v in/rip_up.exr | grep -q 'roundingmode: 1' || fail "in/rip_up.exr does not round up"

# Stereo in one part: the other view's channels, named by OpenEXR's rule (diffuse.right.R) or
# Nuke's (right.diffuse.R), come out under the default view's names, with their own types.
oiiotool --fail 0 --warn 0 ref/mv_left.exr out/mve_left.exr --diff ref/mv_left.exr out/mvn_left.exr --diff \
    ref/mv_right.exr out/mve_right.exr --diff ref/mv_right.exr out/mvn_right.exr --diff >diff.out 2>&1 ||
    { cat diff.out >&2; fail "a view's values differ"; }
[ "$(grep -c '^PASS' diff.out)" -eq 4 ] || { cat diff.out >&2; fail "not every view compared"; }
for c in mve_left mve_right mvn_left mvn_right; do
    case "$(field layouts.txt "out/$c.exr")" in
    *"channel list: R (float), G (float), B (float), diffuse.R (half)"*) ;;
    *) fail "out/$c.exr: $(field layouts.txt "out/$c.exr")" ;;
    esac
done

# What the reads said: the default multi-part read warns, naming the parts it left out and
# why; a part or view chosen by the graph is a note.
has_err() { grep -F -- "$2" copy.err | grep -qF -- "'$1'" || { cat copy.err >&2; fail "read '$1' does not say '$2'"; }; }
has_err r_mp_default "warning: read 'r_mp_default': 'in/multipart.exr': read part 0 'beauty', part 1 'aov'"
has_err r_mp_default "not used: part 2 'depth' (data window 64x48+0+0, display window 64x48+0+0)"
has_err r_mp_default "part 3 'proxy' (data window 32x24+0+0"
has_err r_mp_default 'set "part" to read another'
has_err r_mp_depth "note: read 'r_mp_depth': 'in/multipart.exr': read part 2 'depth'"
has_err r_mp_want "read part 2 'depth'"
has_err r_mvp_right "read part 1 'rgba.right', view 'right'"
has_err r_mve_right "view 'right'"
# An unfinished multi-part file (parts 2 and 3 never written) reads its whole parts, naming the
# others; `info` marks them; a read that asks for one is refused (below).
has_err r_unf_default "warning: read 'r_unf_default': 'in/unfinished.exr': read part 0 'beauty', part 1 'aov'"
has_err r_unf_default "part 2 'depth' (unfinished or damaged: its pixels are missing), part 3 'extra' (unfinished"
has_err r_unf_aov "read part 1 'aov'"
"$NPRFX" info in/unfinished.exr >info_unf.txt 2>&1 || fail "info of an unfinished file failed"
grep -q "part 3 'extra': .*unfinished or damaged (its pixels are missing): not read" info_unf.txt ||
    { cat info_unf.txt >&2; fail "info does not mark the unfinished parts"; }
grep -q "damaged" <(grep -v "^    part" info_unf.txt) && { cat info_unf.txt >&2; fail "info reports the file as an error"; }
# uint ids above 2^24 read exactly (their copy is compared above), with nothing to say.
grep -F "'r_uint_big'" copy.err && fail "the read of uint ids above 2^24 has something to say"
# Rendered by strips, too.
printf '{"frames": "1", "nodes": {"r": {"node": "read", "path": "in/uint_big.exr"}, "b": {"node": "blend", "inputs": {"base": "r:R", "layer": "r:id"}}, "w": {"node": "write", "inputs": {"image": "b"}, "path": "out/strips.exr"}}}\n' >strips.json
"$NPRFX" run strips.json --strip-rows 2 --stats >strips.out 2>strips.err || { cat strips.err >&2; fail "the strips read failed"; }
grep -q "rendered by strips of 2 rows" strips.out || fail "strips.json was not rendered by strips"
grep -qF "'in/uint_big.exr'" strips.err && { cat strips.err >&2; fail "a read by strips of uint ids has something to say"; }

# Refusals, each naming the file and what is wrong; all graphs in one run, each fails.
err_graph() { # NAME FILE PART VIEW
    {
        printf '{"frames": "1", "nodes": {"plate": {"node": "read", "path": "in/%s"' "$2"
        [ "$3" = - ] || printf ', "part": "%s"' "$3"
        [ "$4" = - ] || printf ', "view": "%s"' "$4"
        printf '},\n "out": {"node": "write", "inputs": {"image": "plate"}, "path": "out/x.exr"}}}\n'
    } >"$1.json"
}
err_graph e_deep deep.exr - -
err_graph e_part multipart.exr nope -
err_graph e_index multipart.exr 7 -
err_graph e_view mv_parts.exr - centre
err_graph e_view1 mv_exr.exr - centre
err_graph e_flat scan_float.exr - left
err_graph e_both mv_parts.exr rgba.right left
err_graph e_unf unfinished.exr depth -
# Inputs of one size at different origins: the error names the windows.
cat >e_origin.json <<'JSON'
{"frames": "1", "nodes": {
  "a": {"node": "read", "path": "in/scan_float.exr"},
  "b": {"node": "read", "path": "in/neg_origin.exr"},
  "mix": {"node": "blend", "inputs": {"base": "a:R,G,B", "layer": "b:R,G,B"}},
  "out": {"node": "write", "inputs": {"image": "mix"}, "path": "out/x.exr"}}}
JSON
rc=0
"$NPRFX" run e_deep.json e_part.json e_index.json e_view.json e_view1.json e_flat.json e_both.json \
    e_origin.json e_unf.json >last.out 2>last.err || rc=$?
[ "$rc" -ne 0 ] || fail "the graphs that must fail did not"
[ ! -e out/x.exr ] || fail "a refused read wrote a file"
says() { # GRAPH TEXT: the failure of GRAPH says TEXT
    grep -F "$1.json:" last.err | grep -qF -- "$2" || fail_log "$1.json fails without saying '$2'"
}
says e_deep "'in/deep.exr' part 0 holds deep data"
says e_deep "oiiotool 'in/deep.exr' --flatten -o flat.exr"
says e_part "'in/multipart.exr' has no part 'nope' (parts, by index and name: 0 'beauty', 1 'aov', 2 'depth', 3 'proxy')"
says e_index "has no part '7'"
says e_view "'in/mv_parts.exr' has no view 'centre' (views: left, right)"
says e_view1 "'in/mv_exr.exr' has no view 'centre' (views: left, right)"
says e_unf "'in/unfinished.exr' is damaged: part 2, chunk at scanline 0"
says e_flat "'in/scan_float.exr' has no view 'left': it is not a multi-view file"
says e_both "part 1 'rgba.right' is view 'right', not view 'left'"
says e_origin "input 'layer' has data window 64x48-10-20 but input 'base' has 64x48+0+0"
echo "corpus_valid: all checks passed"
