#!/usr/bin/env bash
# Regenerate the gallery of docs/styles.md: every style graph of samples/graphs/ (those with a
# "look" node) on the Blender shots at 1280x720, as
#   docs/images/styles/NAME.jpg        crossing, frame 12, 1280x720
#   docs/images/styles/NAME-strip.jpg  crossing, frames 4, 8 and 12 side by side (640x360 each)
#   docs/images/styles/NAME-dolly.jpg  dolly, frame 12, 1280x720 (a second shot, with sky)
#   docs/images/styles/NAME-lights.jpg three lights at two sizes (below)
# usage: docs/make_gallery.sh build/nprfx [HD_DIR [STYLE ...]]   (STYLE: only these graphs)
# HD_DIR (default build/hd) holds the 1280x720 plates; when they are missing they are rendered
# first with Blender (samples/blender/make_plates.py --res 1280x720, frames 1-12 of crossing and
# dolly: about 10 minutes on 2 quiet cores; apt-get install blender). Only frames 1-12 are read, so
# plates rendered for all 24 frames serve as well. The styles themselves take a few minutes.
set -euo pipefail
NPRFX=$(realpath "${1:?usage: docs/make_gallery.sh PATH/TO/nprfx [HD_DIR]}")
here=$(cd "$(dirname "$0")" && pwd)
src=$(cd "$here/.." && pwd)
hd=$(realpath -m "${2:-$src/build/hd}")
shift $(( $# < 2 ? $# : 2 ))
only=" $* "
# The same look on another renderer's plates, no Blender needed: watercolor on the synthetic
# orbit scene (nprfx synth) written under Arnold's names and conventions (Cryptomatte object ids,
# one motion vector to the next frame, no diffuse light pass) and under Blender's, frame 12:
#   docs/images/styles/watercolor-arnold.jpg   the Arnold layout, 1280x720
#   docs/images/styles/layouts.jpg             Blender's and Arnold's side by side (640x360 each)
# usage: docs/make_gallery.sh build/nprfx HD_DIR layouts   (only this picture)
layouts_picture() {
  local tmp out="$here/images/styles"
  tmp=$(mktemp -d)
  mkdir -p "$out"
  for layout in blender arnold; do
    "$NPRFX" synth orbit --layout $layout --size 1280x720 --frames 1-12 \
      -o "$tmp/$layout/orbit.####.exr" > /dev/null
    "$NPRFX" run "$src/samples/graphs/watercolor.json" --set "plate.path=$tmp/$layout/orbit.####.exr" \
      --shot 1-12 --output-dir "$tmp/run_$layout" --quiet
  done
  local f=out/watercolor/watercolor.0012.png
  oiiotool "$tmp/run_arnold/$f" --ch R,G,B --compression jpeg:90 -o "$out/watercolor-arnold.jpg"
  oiiotool "$tmp/run_blender/$f" --ch R,G,B --resize 640x360 "$tmp/run_arnold/$f" --ch R,G,B \
    --resize 640x360 --mosaic 2x1 --compression jpeg:90 -o "$out/layouts.jpg"
  rm -rf "$tmp"
  echo "make_gallery: layouts"
}
if [ "$only" = " layouts " ]; then layouts_picture; exit 0; fi

# Every style in three lights at two sizes, no Blender needed: the synthetic orbit scene (nprfx
# synth, Blender's layout) lit by the sun, by a strong point light (HDR highlights up to ~40) and
# low key (most of it below 0.1), frame 2, at 1280x720 (top row, shown at 640x360) and as a
# 320x180 proxy (bottom row, enlarged to 640x360), left to right sun, point, low key:
#   docs/images/styles/NAME-lights.jpg
# usage: docs/make_gallery.sh build/nprfx HD_DIR lights [STYLE ...]   (only these pictures)
lights_pictures() {
  local tmp out="$here/images/styles" g name preview l s args # $1: " NAME ... " or "" (all)
  tmp=$(mktemp -d)
  mkdir -p "$out"
  for l in sun point lowkey; do
    for s in 1280x720 320x180; do
      "$NPRFX" synth orbit --layout blender --light $l --size $s --frames 1-2 \
        -o "$tmp/plates/$l-$s/orbit.####.exr" > /dev/null
    done
  done
  for g in $(style_graphs "$src"); do
    name=$(basename "$g" .json)
    [ -z "$1" ] || [[ "$1" == *" $name "* ]] || continue
    preview=$(grep '"image": *"look"' "$g" | grep -o '"preview": *"[^"]*"' | sed 's/.*"\([^"]*\)"$/\1/')
    args=()
    for s in 1280x720 320x180; do
      for l in sun point lowkey; do
        "$NPRFX" run "$g" --set "plate.path=$tmp/plates/$l-$s/orbit.####.exr" --shot 1-2 --frames 2 \
          --output-dir "$tmp/$name-$l-$s" --quiet
        args+=("$tmp/$name-$l-$s/${preview//####/0002}" --ch R,G,B --resize 640x360)
      done
    done
    oiiotool "${args[@]}" --mosaic 3x2 --compression jpeg:85 -o "$out/$name-lights.jpg"
    echo "make_gallery: $name in three lights"
  done
  rm -rf "$tmp"
}
. "$src/tests/lib/styles.sh" # style_graphs: what counts as a style graph, in one place
if [[ "$only" == " lights "* ]]; then
  sel=${only#" lights"}
  [ "$sel" = " " ] && sel=""
  lights_pictures "$sel"
  exit 0
fi

for shot in crossing dolly; do
  if [ ! -f "$hd/$shot/$shot.0012.exr" ]; then
    command -v blender >/dev/null || { echo "make_gallery: $hd/$shot has no plates and blender is not installed (apt-get install blender)" >&2; exit 1; }
    echo "make_gallery: rendering $shot at 1280x720 with Blender into $hd"
    blender -b --factory-startup --python "$src/samples/blender/make_plates.py" -- \
      --out "$hd" --res 1280x720 --shots "$shot" --frame-range 1-12 >"$hd.$shot.log" 2>&1
  fi
done
out="$here/images/styles"
mkdir -p "$out"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
for g in $(style_graphs "$src"); do
  name=$(basename "$g" .json)
  [ "$only" = "  " ] || [[ "$only" == *" $name "* ]] || continue
  for shot in crossing dolly; do
    # the graph's own write node writes the PNG previews
    "$NPRFX" run "$g" --set "plate.path=$hd/$shot/$shot.####.exr" --shot 1-12 \
      --output-dir "$tmp/$name-$shot" --quiet
  done
  # the preview of the write node of "look" (a graph may write other images too)
  preview=$(grep '"image": *"look"' "$g" | grep -o '"preview": *"[^"]*"' | sed 's/.*"\([^"]*\)"$/\1/')
  frame() { printf '%s/%s' "$1" "${preview//####/$2}"; }
  c=$(frame "$tmp/$name-crossing" 0012)
  d=$(frame "$tmp/$name-dolly" 0012)
  oiiotool "$c" --ch R,G,B --compression jpeg:90 -o "$out/$name.jpg"
  oiiotool "$d" --ch R,G,B --compression jpeg:90 -o "$out/$name-dolly.jpg"
  args=()
  for f in 0004 0008 0012; do
    args+=("$(frame "$tmp/$name-crossing" $f)" --ch R,G,B --resize 640x360)
  done
  oiiotool "${args[@]}" --mosaic 3x1 --compression jpeg:90 -o "$out/$name-strip.jpg"
  echo "make_gallery: $name"
done
[ "$only" = "  " ] || [[ "$only" == *" layouts "* ]] && layouts_picture
if [ "$only" = "  " ]; then lights_pictures ""; else lights_pictures "$only"; fi
ls -la "$out"
