#!/usr/bin/env bash
# Every shipped style graph (samples/graphs/*.json with a read node), unedited but for
# plate.path and --shot, renders on the same scene under every renderer's layout
# (nprfx synth --layout) to the pixels of the Blender layout carrying the same numbers,
# bit for bit. "The same numbers" (exr_plates.py blender-as) is what a layout's conventions
# give the engine that Blender's do not:
#   - object ids decoded from Cryptomatte (Arnold, Karma, V-Ray, Redshift) are the object
#     names' hashes, not IndexOB's 1, 2, 3: the id-seeded looks change pattern, not quality;
#   - no diffuse light pass (Arnold, RenderMan, Karma, Nuke): beauty stands in for it;
#   - one vector to the next frame (Arnold, Karma, Redshift): motion_prev is its opposite;
#   - Nuke's depth is 1/z: read back as 1/(1/z).
# Where a conversion changes the numbers, the change is bounded against the render without it:
#   - motion_prev as the opposite of motion_next (Redshift against V-Ray's true motion_prev):
#     per output at most 2% of pixels differ by more than 0.02 and none by more than 0.25
#     (coherent_noise_fig2 shows the frame difference itself: 10%);
#   - 1/(1/z) against z (Nuke against RenderMan): no pixel differs by more than 1e-5.
# And every style runs on a plate with only beauty and depth, each fallback said once.
set -u
NPRFX=$1; SRC=$2; W=$3
rm -rf "$W"; mkdir -p "$W"; cd "$W" || exit 1
passes=0; fails=0
pass() { passes=$((passes+1)); }
fail() { echo "FAIL: $*"; fails=$((fails+1)); }
command -v oiiotool > /dev/null || { echo "FAIL: oiiotool (openimageio-tools) is needed"; exit 1; }
command -v python3 > /dev/null || { echo "FAIL: python3 is needed"; exit 1; }
plates() { python3 "$SRC/tests/cli/exr_plates.py" "$@"; }
export NPRFX_THREADS=1 # two runs at a time below

SIZE=128x72
LAYOUTS="arnold renderman karma vray redshift nuke"
for L in blender $LAYOUTS; do
  "$NPRFX" synth orbit --layout $L --size $SIZE --frames 1-2 -o $L/orbit.####.exr > /dev/null ||
    { echo "FAIL: synth --layout $L"; exit 1; }
done
# The Blender layout carrying each layout's numbers (and, for the bounds, without the conversion).
changes() {
  case $1 in
    renderman) echo nodiffuse ;; vray) echo cryptoids ;;
    arnold|karma) echo nodiffuse,cryptoids,prevfromnext ;; redshift) echo cryptoids,prevfromnext ;;
    nuke) echo nodiffuse,inversedepth ;;
  esac
}
for L in $LAYOUTS; do
  plates blender-as "$(changes $L)" as_$L blender/orbit.000[12].exr ||
    { echo "FAIL: blender-as $L"; exit 1; }
done
# A plate with only beauty and depth: an Arnold render's R, G, B, A and Z.
mkdir -p bd
for f in 0001 0002; do
  oiiotool arnold/orbit.$f.exr --ch R,G,B,A,Z -o bd/orbit.$f.exr > /dev/null 2>&1 ||
    { echo "FAIL: oiiotool"; exit 1; }
done

GRAPHS=; STYLES=
for g in "$SRC"/samples/graphs/*.json; do
  grep -Eq '"node": *"read"' "$g" && { GRAPHS="$GRAPHS $g"; STYLES="$STYLES $(basename "$g" .json)"; }
done
[ "$(echo $STYLES | wc -w)" -ge 20 ] && pass || fail "only these style graphs: $STYLES"

# Every style on each plate: one run per plate (out/PLATE/), two at a time. Sizes in the plate's
# pixels (--design-width off): at the graphs' 1280 the small plates would draw marks too fine for
# a layout's conversions to show.
for P in $LAYOUTS $(for L in $LAYOUTS; do echo as_$L; done) blender; do echo $P; done |
  xargs -P 2 -I{} sh -c '"$0" run $1 --set plate.path="$PWD/$2/orbit.####.exr" --shot 1-2 --design-width off \
    --output-dir "out/$2" > "$2.log" 2>&1 || echo "$2" >> failed.txt' "$NPRFX" "$GRAPHS" {}
[ ! -s failed.txt ] && pass || while read -r P; do fail "the styles on the $P plate:"; cat $P.log; done < failed.txt
FILES=$(cd out/blender && find . -name '*.exr' | sed 's,^\./,,' | sort)
[ "$(echo $FILES | wc -w)" -ge 40 ] && pass || fail "the styles wrote only: $FILES"
for P in $LAYOUTS; do
  [ "$(cd out/$P && find . -name '*.exr' | sed 's,^\./,,' | sort)" = "$FILES" ] && pass ||
    fail "the styles on the $P plate wrote other files than on the Blender plate"
done
pick() { printf '%s\n' $FILES | grep "$@"; } # the outputs of some styles

for L in $LAYOUTS; do
  plates same out/$L out/as_$L $FILES > d.txt 2>&1 && pass || { fail "$L layout:"; cat d.txt; }
done
# The bounds: coherent_noise_fig2's frame difference shows the change itself.
plates close out/as_vray out/as_redshift 0.02 2 0.25 $(pick -v fig2/) > d.txt 2>&1 && pass ||
  { fail "motion_prev from motion_next:"; cat d.txt; }
plates close out/as_vray out/as_redshift 0.02 10 0.25 $(pick fig2/) > d.txt 2>&1 && pass ||
  { fail "motion_prev from motion_next, coherent_noise_fig2:"; cat d.txt; }
plates close out/as_renderman out/as_nuke 1e-5 0 1e-5 $FILES > d.txt 2>&1 && pass ||
  { fail "1/(1/z) for z:"; cat d.txt; }

# The comparisons can fail: the same numbers matter. The Cryptomatte ids re-seed chalk's
# strokes (Arnold against Blender's IndexOB), the missing diffuse pass changes gabor_dolly's
# hatching (RenderMan against Blender), and each conversion changes pixels.
differs() { # PLATE_A PLATE_B FILE WHAT
  plates same out/$1 out/$2 $3 > d.txt 2>&1 && fail "$4: $3 on $1 and $2 compared the same" || pass
}
differs arnold blender "$(pick chalk.0002)" "Cryptomatte ids"
differs renderman blender "$(pick gabor_dolly/hatching.0002)" "no diffuse light"
differs as_vray as_redshift "$(pick toon.0002)" "motion_prev from motion_next"
differs as_renderman as_nuke "$(pick stippling.0002)" "1/(1/z)"
plates close out/arnold out/blender 0.02 5 1 "$(pick chalk.0002)" > d.txt 2>&1 &&
  fail "the Cryptomatte ids changed under 5% of chalk's pixels" || pass

# Beauty and depth only, a run per style: each missing AOV a style needs is said once, with what
# stands in.
for s in $STYLES; do echo $s; done |
  xargs -P 2 -I{} sh -c '"$0" run "$1/samples/graphs/$2.json" --set plate.path="$PWD/bd/orbit.####.exr" \
    --shot 1-2 --output-dir "out/bd/$2" > "bd_$2.log" 2>&1 || echo "$2" >> bd_failed.txt' "$NPRFX" "$SRC" {}
[ ! -s bd_failed.txt ] && pass || while read -r s; do fail "$s on beauty and depth:"; cat bd_$s.log; done < bd_failed.txt
for s in $STYLES; do
  dup=$(grep "^nprfx run: warning: plate" "bd_$s.log" | sort | uniq -d)
  [ -z "$dup" ] && [ -n "$(find out/bd/$s -name '*.0002.exr')" ] && pass ||
    fail "$s on beauty and depth: no frame 2, or said twice: $dup"
done
for w in "has no id: the inputs that take it are left unconnected" \
  "has no motion vectors: optical flow on its beauty stands in" \
  "has no position, rest or uv: a camera-space position from its depth stands in"; do
  grep -lF "warning: plate 'plate' (arnold profile) $w" bd_*.log > /dev/null && pass ||
    fail "no style said: $w"
done
echo "$passes passed, $fails failed"
[ $fails -eq 0 ]
