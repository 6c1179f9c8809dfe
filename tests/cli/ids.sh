#!/usr/bin/env bash
# Object ids keep all 32 bits from a uint channel through the nodes that compare them and back
# out (docs/design.md, "Object ids"). The orbit plate's ids 1, 2, 3 become uint 2^28 + 1, + 2,
# + 3 (one float when rounded: 268435456) and 0x7f800001.. (NaN bit patterns, signalling ones);
# the same plates with every object given one id are the merged references.
#  - the id channel written back is the file's, bit for bit (uint);
#  - lines and matte, which use ids only to tell objects apart, draw on the 32-bit ids exactly
#    what they draw on ids 1, 2, 3, and something else on the merged plate;
#  - gabor-splat, stipple and pam-splat (kernels, dots and splats cut at object edges, and seeded
#    per object) render the three objects otherwise than the merged one, NaN ids included.
set -u
NPRFX=$1; SRC=$2; W=$3
. "$SRC/tests/cli/lib/check.sh"
[ -n "${NPRFX_MAKE_EXR:-}" ] || { echo "SKIP: no nprfx-make-exr (the tests' OpenEXR program)"; exit 77; }
work_in "$W"
mkdir in
"$NPRFX" synth orbit -o in/s.exr --size 160x90 --frames 24 >/dev/null || fail "synth failed"
"$NPRFX_MAKE_EXR" --uint-ids 0 in/s.exr in/small.exr &&
    "$NPRFX_MAKE_EXR" --uint-ids 0x10000000 in/s.exr in/hi.exr &&
    "$NPRFX_MAKE_EXR" --uint-ids 0x10000000 --merge in/s.exr in/hi_merged.exr &&
    "$NPRFX_MAKE_EXR" --uint-ids 0x7f800000 in/s.exr in/nan.exr &&
    "$NPRFX_MAKE_EXR" --uint-ids 0x7f800000 --merge in/s.exr in/nan_merged.exr ||
    fail "nprfx-make-exr could not write the uint plates"

for p in small hi hi_merged nan nan_merged; do
    cat >"$p.json" <<G
{"frames": "1", "nodes": {
 "plate": {"node": "read", "path": "in/$p.exr"},
 "lines": {"node": "lines", "inputs": {"id": "plate:id"}, "params": {"width": 1.5}},
 "matte": {"node": "matte", "inputs": {"id": "plate:id"}, "params": {"background_id": 0}},
 "gabor": {"node": "gabor-splat", "inputs": {"anchor": "plate:Pref", "depth": "plate:Z", "id": "plate:id"},
           "params": {"radius": 6, "frequency": 0.15, "orientation": 30, "seed": 3, "depth_test": "off"}},
 "stipple": {"node": "stipple", "inputs": {"tone": "plate:diffuse", "uv": "plate:UV.U,UV.V", "id": "plate:id"},
             "params": {"mode": "uniform", "size": 3, "tile": 6}},
 "pam": {"node": "pam-splat", "inputs": {"anchor": "plate:Pref", "tone": "plate:diffuse", "color": "plate:R,G,B,A",
         "depth": "plate:Z", "id": "plate:id"}, "params": {"size": 12, "density": 5, "seed": 3}},
 "w_id": {"node": "write", "inputs": {"image": "plate:id"}, "path": "out/$p/id.exr"},
 "w_lines": {"node": "write", "inputs": {"image": "lines"}, "path": "out/$p/lines.exr"},
 "w_matte": {"node": "write", "inputs": {"image": "matte"}, "path": "out/$p/matte.exr"},
 "w_gabor": {"node": "write", "inputs": {"image": "gabor"}, "path": "out/$p/gabor.exr"},
 "w_stipple": {"node": "write", "inputs": {"image": "stipple"}, "path": "out/$p/stipple.exr"},
 "w_pam": {"node": "write", "inputs": {"image": "pam"}, "path": "out/$p/pam.exr"}}}
G
    expect_rc 0 "$NPRFX" run "$p.json" --quiet
    lacks last.err "2^24"
done

# The ids written back: uint, the file's bits (the plate's float ids k mapped to base + k; OIIO
# converts uint through float, so its dump of the written file is read against that).
oiiotool in/s.exr --ch id -o s_id.exr || fail "oiiotool could not extract the ids"
oiiotool --dumpdata s_id.exr | awk '/Pixel/ { print $4 }' >s_id.txt
for pb in small:0 hi:268435456 nan:2139095040; do
    p=${pb%:*} base=${pb#*:}
    case "$(iinfo -v "out/$p/id.exr" | grep 'channel list')" in *"id (uint)"* | *"channel list: id"*) ;;
    *) fail "out/$p/id.exr: the id channel is not uint" ;; esac
    iinfo "out/$p/id.exr" | grep -q uint || fail "out/$p/id.exr is not uint"
    oiiotool --dumpdata "out/$p/id.exr" | awk '/Pixel/ { print $4 }' >got.txt
    awk -v b="$base" '{ printf "%.0f\n", $1 == 0 ? 0 : b + $1 }' s_id.txt >want.txt
    [ -s want.txt ] && cmp -s want.txt got.txt ||
        { diff want.txt got.txt | head -5 >&2; fail "out/$p/id.exr holds other ids than in/$p.exr"; }
done

same() { # A B WHAT: the two images are equal
    expect_rc 0 "$NPRFX" diff "$1" "$2" --fail 0 --warn 0 -q
}
differ() { # A B WHAT: they differ (on some pixels)
    local rc=0
    "$NPRFX" diff "$1" "$2" --fail 0 --warn 0 -q >last.out 2>&1 || rc=$?
    [ "$rc" -eq 2 ] || { cat last.out >&2; fail "$3: $1 and $2 should differ (diff exited $rc)"; }
}
for n in lines matte; do
    same "out/small/$n.exr" "out/hi/$n.exr"
    same "out/small/$n.exr" "out/nan/$n.exr"
done
differ out/small/lines.exr out/hi_merged/lines.exr "lines see the merged objects as one"
for n in gabor stipple pam; do
    differ "out/hi/$n.exr" "out/hi_merged/$n.exr" "$n on ids 2^28 + 1, 2, 3"
    differ "out/nan/$n.exr" "out/nan_merged/$n.exr" "$n on NaN-pattern ids"
done
echo "ids: passed"
