#!/usr/bin/env bash
# Regenerate the footage pictures of docs/styles.md: every footage graph of samples/graphs/
# (footage_*.json) on 1920x1080 footage that has no AOVs, shown at 1280x720, as
#   docs/images/styles/footage_NAME.jpg        the orbit scene (nprfx synth), frame 6
#   docs/images/styles/footage_NAME-strip.jpg  frames 2, 4 and 6 side by side (640x360 each)
# The footage is the synthetic orbit scene's colour alone, written as 8-bit sRGB PNG frames with
# oiiotool (a sphere turning and orbiting a box before a checkered backdrop): made here, in
# WORK_DIR (default build/footage_hd), when missing. Takes a few minutes on 2 cores.
# usage: docs/make_footage_gallery.sh build/nprfx [WORK_DIR]
set -euo pipefail
NPRFX=$(realpath "${1:?usage: docs/make_footage_gallery.sh PATH/TO/nprfx [WORK_DIR]}")
here=$(cd "$(dirname "$0")" && pwd)
src=$(cd "$here/.." && pwd)
work=$(realpath -m "${2:-$src/build/footage_hd}")
mkdir -p "$work"
if [ ! -f "$work/orbit.0006.png" ]; then
  "$NPRFX" synth orbit --frames 1-6 --size 1920x1080 -o "$work/orbit.####.exr" >/dev/null
  for f in 1 2 3 4 5 6; do
    oiiotool "$work/orbit.000$f.exr" --ch R,G,B --colorconvert linear sRGB -d uint8 \
      -o "$work/orbit.000$f.png"
  done
fi
out="$here/images/styles"
mkdir -p "$out"
for g in "$src"/samples/graphs/footage_*.json; do
  name=$(basename "$g" .json)
  "$NPRFX" run "$g" --set "plate.path=$work/orbit.####.png" --shot 1-6 \
    --output-dir "$work/$name" --quiet
  png() { find "$work/$name" -name "*.000$1.png" | head -n 1; }
  oiiotool "$(png 6)" --ch R,G,B --resize 1280x720 -o "$out/$name.jpg"
  oiiotool "$(png 2)" --ch R,G,B --resize 640x360 "$(png 4)" --ch R,G,B --resize 640x360 \
    "$(png 6)" --ch R,G,B --resize 640x360 --mosaic 3x1 -o "$out/$name-strip.jpg"
done
ls -l "$out"/footage_*
