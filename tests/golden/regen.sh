#!/usr/bin/env bash
# Regenerate tests/golden/ with the given nprfx binary:
#   tests/golden/regen.sh build/nprfx
# - golden/*.exr: every tests/graphs/*.json;
# - golden/styles/NAME/...: every style graph of samples/graphs/ on the synthetic plates
#   (tests/lib/styles.sh says how; tests/cli/styles.sh compares with them).
# Only after checking that the change in output is intended; say why in the commit message.
set -euo pipefail
NPRFX=$(realpath "${1:?usage: tests/golden/regen.sh PATH/TO/nprfx}")
here=$(cd "$(dirname "$0")" && pwd)
src=$(cd "$here/../.." && pwd)
. "$src/tests/lib/styles.sh"
rm -f "$here"/*.exr
for g in "$here"/../graphs/*.json; do
  "$NPRFX" run "$g" --output-dir "$here/.." --quiet
done
rm -rf "$here/styles"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
style_plates "$NPRFX" "$tmp"
for g in $(style_graphs "$src"); do
  name=$(basename "$g" .json)
  style_render "$NPRFX" "$g" "$tmp" "$tmp/out-$name"
  mkdir -p "$here/styles/$name"
  (cd "$tmp/out-$name" && find . -name '*.exr' | while read -r f; do
     mkdir -p "$here/styles/$name/$(dirname "$f")"; cp "$f" "$here/styles/$name/$f"; done)
done
ls "$here"/*.exr | wc -l | xargs echo "golden files:"
find "$here/styles" -name '*.exr' | wc -l | xargs echo "style golden files:"
