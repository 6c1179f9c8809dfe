#!/usr/bin/env bash
# Regenerate the small pictures of docs/styles.md: frame 12 of every sample graph that is not a
# style (the styles, graphs with a "look" node, are in the 1280x720 gallery of
# docs/make_gallery.sh), each PNG preview it writes copied to docs/images/<graph>-<preview>.png.
# Usage: docs/make_pictures.sh build/nprfx
set -euo pipefail
NPRFX=$(realpath "${1:?usage: docs/make_pictures.sh PATH/TO/nprfx}")
here=$(cd "$(dirname "$0")" && pwd)
. "$here/../tests/lib/styles.sh" # style_graphs: the styles, pictured by make_gallery.sh
styles=$(style_graphs "$here/..")
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
for g in "$here"/../samples/graphs/*.json; do
  name=$(basename "$g" .json)
  case " $(echo $styles) " in *" $g "*) continue ;; esac
  "$NPRFX" run "$g" --frames 12 --output-dir "$tmp/$name" --quiet
  find "$tmp/$name" -name '*.0012.png' | while read -r png; do
    cp "$png" "$here/images/$name-$(basename "$png" .0012.png).png"
  done
done
ls "$here"/images
