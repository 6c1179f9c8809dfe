#!/usr/bin/env bash
# The style graphs of samples/graphs/ (those with a "look" node; tests/lib/styles.sh):
# - golden: each renders on the synthetic plates (nprfx synth dolly --layout blender, only the
#   read path changed) as its golden files in tests/golden/styles/ (fail 1e-5, hardfail 1e-4);
# - background (on the same scene at 512x288, frames 1-4): where the matte is 0 the look is the
#   paper (within 1e-5), 12 px away from the objects (watercolor's edges wobble and bleed past
#   the silhouette on purpose);
# - tone: the look's mean luminance, 4 px inside the objects, never falls (by more than 0.04) as
#   the light (DiffDir) rises (nprfx measure's tone_monotone, ten steps of the light);
# - coherence: on the Blender crossing shot (frames 1-6, up to 32 px/frame; pixels moving over
#   0.5 px a frame, as static ones are alike in every variant), the warp error along
#   the motion vectors is below that of the same graph with its patterns stuck to the screen
#   (--variant shower-door) and of the same graph drawn anew every frame (--variant white).
# measure is told the plate (--plate plate): a style may read other images too (pam-splat's PAM).
# Regenerate the goldens (and say why in the commit): tests/golden/regen.sh BUILD/nprfx
set -u
NPRFX=$1; SRC=$2; W=$3
. "$SRC/tests/lib/styles.sh"
rm -rf "$W"; mkdir -p "$W/plates"
passes=0; fails=0
fail() { echo "FAIL: $*"; fails=$((fails+1)); }
pass() { passes=$((passes+1)); }
style_plates "$NPRFX" "$W/plates" || { echo "FAIL: synth"; exit 1; }
mkdir -p "$W/big"
style_measure_plates "$NPRFX" "$W/big" || { echo "FAIL: synth"; exit 1; }
graphs=$(style_graphs "$SRC")
[ -n "$graphs" ] || { echo "FAIL: no style graph in samples/graphs"; exit 1; }
for g in $graphs; do
  name=$(basename "$g" .json)
  # golden files
  if style_render "$NPRFX" "$g" "$W/plates" "$W/out-$name"; then
    gold="$SRC/tests/golden/styles/$name"
    [ -d "$gold" ] || fail "$name: no golden files (tests/golden/regen.sh)"
    for f in $(cd "$gold" 2>/dev/null && find . -name '*.exr'); do
      if "$NPRFX" diff "$gold/$f" "$W/out-$name/$f" --fail 1e-5 --failpercent 0 --hardfail 1e-4 \
           --warn 1e-5 --out "$W/out-$name/$f.diff.exr" --scale 1000 >"$W/$name.diff.txt" 2>&1; then
        pass
      else
        fail "$name: $f differs from its golden file:"; cat "$W/$name.diff.txt"
      fi
    done
  else
    fail "$name did not render on the synthetic plates"
  fi
  # background and tone on the synthetic plates
  m=$("$NPRFX" measure "$g" --node look --plate plate --set "plate.path=$W/big/dolly.####.exr" \
        --shot "$STYLE_MEASURE_FRAMES" --matte matte --paper paper --margin 12 --inset 4 \
        --light plate:DiffDir.R 2>"$W/$name.measure.log")
  if [ $? -ne 0 ]; then fail "$name: measure failed"; cat "$W/$name.measure.log"; continue; fi
  bg=$(printf '%s\n' "$m" | awk '$1 == "background_max_diff" {print $2}')
  nbg=$(printf '%s\n' "$m" | awk '$1 == "background_pixels" {print $2}')
  if awk -v d="${bg:-1}" -v n="${nbg:-0}" 'BEGIN {exit !(n > 1000 && d <= 1e-5)}'; then pass
  else fail "$name: background is not the paper (max diff ${bg:-?} over ${nbg:-0} pixels)"; fi
  if printf '%s\n' "$m" | grep -q '^tone_monotone 1$'; then pass
  else fail "$name: the look does not darken with the light: $(printf '%s\n' "$m" | grep tone_curve)"; fi
  # coherence on the Blender crossing shot
  rms() {
    "$NPRFX" measure "$g" --node look --plate plate --shot 1-6 --moving 0.5 --variant "$1" 2>/dev/null |
      awk '$1 == "warp_rms" {print $2}'
  }
  c=$(rms coherent); s=$(rms shower-door); wn=$(rms white)
  echo "$name: warp rms coherent ${c:-?}, shower-door ${s:-?}, white ${wn:-?}"
  if awk -v c="${c:-9}" -v s="${s:-0}" -v w="${wn:-0}" 'BEGIN {exit !(c < s && c < w)}'; then pass
  else fail "$name: warp error ${c:-?} is not below shower-door ${s:-?} and white ${wn:-?}"; fi
done
echo "$passes passed, $fails failed"
[ $fails -eq 0 ] && [ $passes -gt 0 ]
