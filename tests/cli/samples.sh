#!/usr/bin/env bash
# Every sample graph in samples/graphs/ runs (on its first two frames) and writes every output it
# declares, previews included.
set -u
NPRFX=$1; SRC=$2; W=$3
rm -rf "$W"; mkdir -p "$W"
passes=0; fails=0
. "$SRC/tests/lib/flow.sh"
for g in "$SRC"/samples/graphs/*.json; do
  needs_missing_flow "$NPRFX" "$g" && { echo "skipped $(basename "$g"): no optical flow in this build"; continue; }
  name=$(basename "$g" .json)
  first=$(grep -o '"frames": *"[0-9]*' "$g" | grep -o '[0-9]*$')
  if "$NPRFX" run "$g" --frames "${first:-1}-$(( ${first:-1} + 1 ))" --output-dir "$W/$name" --quiet > "$W/$name.log" 2>&1; then
    n=$(find "$W/$name" -name '*.exr' | wc -l)
    if [ "$n" -ge 2 ]; then passes=$((passes+1)); else echo "FAIL: $name wrote $n EXR files"; fails=$((fails+1)); fi
    for png in $(grep -o '"preview": *"[^"]*"' "$g" | sed 's/.*"\([^"]*\)"$/\1/'); do
      f=$(printf '%s' "$png" | sed "s/####/$(printf %04d "${first:-1}")/")
      [ -s "$W/$name/$f" ] && passes=$((passes+1)) || { echo "FAIL: $name: no preview $f"; fails=$((fails+1)); }
    done
  else
    echo "FAIL: $name:"; cat "$W/$name.log"; fails=$((fails+1))
  fi
done
echo "$passes passed, $fails failed"
[ $fails -eq 0 ] && [ $passes -gt 0 ]
