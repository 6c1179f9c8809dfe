#!/usr/bin/env bash
# Looks in any light (docs/styles.md): every style graph on the synthetic 'orbit' shot lit three
# ways by nprfx synth --light: sun (beauty within [0, 1]), point (a strong point light, HDR
# highlights up to ~40) and lowkey (most of the frame below 0.1).
#  - HDR: under the point light every value of the look is finite, at most twice the beauty's
#    brightest and at least -0.2 (pigment and overlay formulas applied as written for [0, 1]
#    square a highlight of 36 into 1e21 or push it to -5e20; pam-splat's Eq. 10 dips to -0.14
#    on dark saturated colours in any light).
#  - Darkest tone: the inked styles (stippling, cross_hatching, graphite, main) with every
#    surface at tone 0 (the light node's range put above every value) keep texture: ink coverage
#    (mean of 1 - luminance) at most 0.85 and local contrast (the luminance's standard deviation
#    in 8x8-pixel blocks, averaged) at least 0.1. With light.solid_blacks the darkest of the
#    black-ink styles (stippling, cross_hatching) fills: coverage at least 0.95 (so the test can
#    fail; graphite's and main's darkest is their densest lead or colour, never solid black).
#  Run in the low-key light too, every inked style is printed with its darkest tone's figures.
#   tests/cli/lights.sh NPRFX SRC WORK [STYLE ...]
set -u
NPRFX=$1; SRC=$2; W=$3; shift 3
rm -rf "$W"; mkdir -p "$W"; cd "$W" || exit 1
. "$SRC/tests/lib/styles.sh"
fails=0
fail() { echo "FAIL: $*"; fails=$((fails+1)); }
command -v oiiotool >/dev/null || { echo "lights: oiiotool is missing (bash .ci/setup)"; exit 1; }

size=320x180
design=640 # the graphs' 1280 look at half size: marks big enough to count at 320 wide
lights="sun point lowkey"
for l in $lights; do
  "$NPRFX" synth orbit --layout blender --light $l --size $size --frames 1-2 \
    -o "plate_$l/orbit.####.exr" > /dev/null || fail "synth --light $l"
done

# stat IMG WHAT [CHANNELS]: the smallest Min or largest Max over the colour channels (R,G,B),
# or the sum of NanCount and InfCount (oiiotool --printstats)
stat() {
  oiiotool "$1" --ch "${3:-R,G,B}" --printstats 2>/dev/null | awk -v w="$2" '
    w == "min" && /Stats Min:/ { m = $3; for (i = 4; i <= 5; i++) if ($i < m) m = $i; print m }
    w == "max" && /Stats Max:/ { m = $3; for (i = 4; i <= 5; i++) if ($i > m) m = $i; print m }
    w == "bad" && /Stats (NanCount|InfCount):/ { s += $3 + $4 + $5 }
    END { if (w == "bad") print s + 0 }'
}

# render GRAPH LIGHT OUT [run options]: frame 2 of the look as OUT.exr
render() {
  local g=$1 l=$2 out=$3 msg; shift 3
  msg=$(style_look "$NPRFX" "$g" "$W/plate_$l/orbit.####.exr" "$out" --design-width $design "$@") ||
    { fail "$(basename "$g") in $l light: $msg"; return 1; }
}

styles=("$@")
[ ${#styles[@]} -eq 0 ] && mapfile -t styles < <(style_graphs "$SRC" | xargs -n1 basename | sed 's/\.json$//')
beauty_max=$(stat plate_point/orbit.0002.exr max ViewLayer.Combined.R,ViewLayer.Combined.G,ViewLayer.Combined.B)
awk -v m="$beauty_max" 'BEGIN { exit !(m > 10) }' ||
  fail "the point light's beauty peaks at $beauty_max: no HDR highlights to test"
printf '%-16s %10s %10s %6s\n' style point-min point-max bad
for n in "${styles[@]}"; do
  g="$SRC/samples/graphs/$n.json"
  render "$g" point "${n}_point" || continue
  pmin=$(stat "${n}_point.exr" min)
  pmax=$(stat "${n}_point.exr" max)
  bad=$(stat "${n}_point.exr" bad)
  printf '%-16s %10.4f %10.4g %6d\n' "$n" "$pmin" "$pmax" "$bad"
  awk -v p="$pmin" -v x="$pmax" -v b="$bad" -v m="$beauty_max" \
    'BEGIN { exit !(b == 0 && p >= -0.2 && x <= 2 * m) }' ||
    fail "$n under the point light: $bad values not finite, range [$pmin, $pmax] (at least -0.2, at most twice the beauty's $beauty_max)"
done

# texture LOOK: ink coverage and local contrast of LOOK.exr
texture() {
  style_lum "$1.exr" "$1_l.exr"
  oiiotool "$1_l.exr" "$1_l.exr" --mul -o "$1_l2.exr"
  local grid=$((${size%x*} / 8))x$((${size#*x} / 8))
  oiiotool "$1_l.exr" --resize:filter=box $grid -o "$1_m1.exr"
  oiiotool "$1_l2.exr" --resize:filter=box $grid -o "$1_m2.exr"
  # the block variance E[l^2] - E[l]^2, floored at 0 against rounding, its square root
  oiiotool "$1_m2.exr" "$1_m1.exr" "$1_m1.exr" --mul --sub --maxc 0 --powc 0.5 -o "$1_sd.exr"
  local lum sd
  lum=$(style_avg "$1_l.exr")
  sd=$(style_avg "$1_sd.exr")
  awk -v l="$lum" -v s="$sd" 'BEGIN { printf "%.3f %.3f\n", 1 - l, s }'
}
dark=(--set light.range=manual --set light.black=1e6 --set light.white=2e6)
printf '\n%-16s %10s %10s %12s %12s\n' style ink contrast solid-ink lowkey-ink
for n in stippling cross_hatching graphite main; do
  [[ " ${styles[*]} " == *" $n "* ]] || continue
  g="$SRC/samples/graphs/$n.json"
  render "$g" sun "${n}_dark" "${dark[@]}" || continue
  render "$g" sun "${n}_solid" "${dark[@]}" --set light.solid_blacks=0.2 || continue
  render "$g" lowkey "${n}_lowkey" || continue
  read -r ink sd < <(texture "${n}_dark")
  read -r sink ssd < <(texture "${n}_solid")
  read -r link lsd < <(texture "${n}_lowkey")
  printf '%-16s %10s %10s %12s %12s\n' "$n" "$ink" "$sd" "$sink" "$link"
  awk -v i="$ink" -v s="$sd" 'BEGIN { exit !(i <= 0.85 && s >= 0.1) }' ||
    fail "$n at the darkest tone: ink coverage $ink (at most 0.85), local contrast $sd (at least 0.1)"
  [[ $n == graphite || $n == main ]] || awk -v i="$sink" 'BEGIN { exit !(i >= 0.95) }' ||
    fail "$n with solid_blacks at the darkest tone: ink coverage $sink (at least 0.95)"
done

[ $fails -eq 0 ] && echo "lights: ok"
exit $((fails > 0))
