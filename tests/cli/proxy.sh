#!/usr/bin/env bash
# A look at any size (docs/design.md §3.6): every style graph rendered on a proxy of the synthetic
# 'orbit' shot (0.25x and 0.5x of the graph's design width) and on a larger plate (1.5x) looks like
# the design-width render resized to it. The metric: the mean absolute difference of the look's
# luminance (Rec.709 weights) averaged over blocks of 32x32 design pixels (8x8 at 0.25x) at most
# PROXY_MAD, and ink coverage (mean of 1 - luminance) within PROXY_INK relative. With the design
# width switched off (sizes in the plate's pixels) the proxies must fail the same metric: that
# shows the test measures what the design width does.
#   [PROXY_DESIGN=1280] [PROXY_LARGE=all] tests/cli/proxy.sh NPRFX SRC WORK [STYLE ...]
# (default: every style graph, design 640, 1.5x for the four finest styles)
set -u
NPRFX=$1; SRC=$2; W=$3; shift 3
PROXY_MAD=0.03
PROXY_INK=0.10
rm -rf "$W"; mkdir -p "$W"; cd "$W" || exit 1
. "$SRC/tests/lib/styles.sh"
fails=0
fail() { echo "FAIL: $*"; fails=$((fails+1)); }
command -v oiiotool >/dev/null || { echo "proxy: oiiotool is missing (bash .ci/setup)"; exit 1; }

# The design: the graphs' own 1280 (PROXY_DESIGN=1280), or by default 640 for a shorter test
# (--design-width 640 draws the graphs' look at half size; the proportions are the same)
design=${PROXY_DESIGN:-640}
full=${design}x$((design * 9 / 16))
sizes="$((design / 4))x$((design * 9 / 64)) $((design / 2))x$((design * 9 / 32)) $((design * 3 / 2))x$((design * 27 / 32))"
grid=$((design / 32))x$((design * 9 / 512)) # blocks of 32x32 design pixels: 8x8 at a quarter
for s in $full $sizes; do
  "$NPRFX" synth orbit --layout blender --size $s --frames 1-2 -o "plate_$s/orbit.####.exr" \
    > /dev/null || fail "synth $s"
done


# render GRAPH SIZE OUT [run options]: frame 2 of the look as OUT.exr
render() {
  local g=$1 s=$2 out=$3 msg; shift 3
  msg=$(style_look "$NPRFX" "$g" "$W/plate_$s/orbit.####.exr" "$out" --design-width $design "$@") ||
    { fail "$(basename "$g") at $s: $msg"; return 1; }
}

# compare NAME SIZE: the metric of NAME_SIZE against NAME_full; prints mad and ink ratio
compare() {
  local n=$1 s=$2
  style_lum "${n}_full.exr" "${n}_fullb.exr" $grid
  style_lum "${n}_$s.exr" "${n}_${s}b.exr" $grid
  oiiotool "${n}_fullb.exr" "${n}_${s}b.exr" --absdiff -o "${n}_${s}d.exr"
  style_lum "${n}_full.exr" "${n}_fulll.exr"
  style_lum "${n}_$s.exr" "${n}_${s}l.exr"
  local mad inkf inks
  mad=$(style_avg "${n}_${s}d.exr")
  inkf=$(style_avg "${n}_fulll.exr")
  inks=$(style_avg "${n}_${s}l.exr")
  awk -v m="$mad" -v f="$inkf" -v s="$inks" 'BEGIN { printf "%.4f %.4f\n", m, (1 - s) / (1 - f) }'
}

styles=("$@")
[ ${#styles[@]} -eq 0 ] && mapfile -t styles < <(style_graphs "$SRC" | xargs -n1 basename | sed 's/\.json$//')
printf '%-16s %-10s %8s %8s\n' style size mad ink
for n in "${styles[@]}"; do
  g="$SRC/samples/graphs/$n.json"
  grep -q '"design_width": *1280' "$g" || { fail "$n.json does not state its design width 1280"; continue; }
  render "$g" $full "${n}_full" || continue
  for s in $sizes; do
    # 1.5x costs most: by default for the styles whose marks are finest (PROXY_LARGE=all: every one)
    if [ "$s" = "${sizes##* }" ] && [ "${PROXY_LARGE:-}" != all ] &&
       [[ " stippling cross_hatching graphite watercolor " != *" $n "* ]]; then continue; fi
    render "$g" $s "${n}_$s" || continue
    read -r mad ink < <(compare "$n" $s)
    printf '%-16s %-10s %8s %8s\n' "$n" $s "$mad" "$ink"
    awk -v m="$mad" -v i="$ink" -v M=$PROXY_MAD -v I=$PROXY_INK \
      'BEGIN { exit !(m <= M && i >= 1 - I && i <= 1 + I) }' ||
      fail "$n at $s: block luminance differs by $mad (at most $PROXY_MAD) or ink ratio $ink (1 +- $PROXY_INK)"
  done
done

# the metric sees sizes in plate pixels: without the design width (the proxy drawn with the full
# render's sizes in pixels) the quarter-size proxy of a
# dotted and a hatched style fails it
for n in stippling cross_hatching; do
  [ -f "${n}_full.exr" ] || continue
  render "$SRC/samples/graphs/$n.json" "${sizes%% *}" "${n}_off" --design-width off || continue
  read -r mad ink < <(compare "$n" off)
  echo "$n at ${sizes%% *} without design width: mad $mad ink $ink"
  awk -v m="$mad" -v i="$ink" -v M=$PROXY_MAD -v I=$PROXY_INK \
    'BEGIN { exit (m <= M && i >= 1 - I && i <= 1 + I) }' ||
    fail "$n at ${sizes%% *} without design width passes the metric ($mad, $ink): the test cannot fail"
done

[ $fails -eq 0 ] && echo "proxy: ok"
exit $((fails > 0))
