#!/usr/bin/env bash
# Regenerate tests/golden/ with the given nprfx binary:
#   tests/golden/regen.sh build/nprfx
# - golden/*.exr: every tests/graphs/*.json;
# - golden/styles/NAME/...: every style graph of samples/graphs/ on the synthetic plates
#   (tests/lib/styles.sh says how; tests/cli/styles.sh compares with them).
# A golden file whose pixels did not change is left as it is (only the header's date would
# differ), so that git shows only real changes. Run it only after checking that a change in
# output is intended, and say why in the commit message.
set -euo pipefail
NPRFX=$(realpath "${1:?usage: tests/golden/regen.sh PATH/TO/nprfx}")
here=$(cd "$(dirname "$0")" && pwd)
src=$(cd "$here/../.." && pwd)
. "$src/tests/lib/styles.sh"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
mkdir -p "$tmp/new/golden" "$tmp/new/styles"
for g in "$here"/../graphs/*.json; do
  "$NPRFX" run "$g" --output-dir "$tmp/new" --quiet
done
style_plates "$NPRFX" "$tmp"
for g in $(style_graphs "$src"); do
  name=$(basename "$g" .json)
  style_render "$NPRFX" "$g" "$tmp" "$tmp/new/styles/$name"
  find "$tmp/new/styles/$name" -name '*.png' -delete
done
# Install: new and changed files; files no graph writes any more are removed.
changed=0
install_tree() { # FROM TO [find options, e.g. -maxdepth 1]
  local from=$1 to=$2; shift 2
  (cd "$from" && find . "$@" -name '*.exr') | while read -r f; do
    if [ -f "$to/$f" ] &&
       "$NPRFX" diff "$to/$f" "$from/$f" --fail 0 --hardfail 0 --warn 0 >/dev/null 2>&1; then
      continue
    fi
    mkdir -p "$(dirname "$to/$f")"; cp "$from/$f" "$to/$f"; echo "updated: $to/${f#./}"
  done
  (cd "$to" && find . "$@" -name '*.exr') | while read -r f; do
    [ -f "$from/$f" ] || { rm "$to/$f"; echo "removed: $to/${f#./}"; }
  done
}
mkdir -p "$here/styles"
install_tree "$tmp/new/golden" "$here" -maxdepth 1
install_tree "$tmp/new/styles" "$here/styles"
find "$here/styles" -type d -empty -delete
ls "$here"/*.exr | wc -l | xargs echo "golden files:"
find "$here/styles" -name '*.exr' | wc -l | xargs echo "style golden files:"
