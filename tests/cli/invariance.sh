#!/usr/bin/env bash
# docs/design.md §4: every node's output is bit-identical across thread counts, tile sizes and render
# orders. Each tests/graphs/*.json renders with 1 thread whole-frame, with 4 threads in 16-pixel
# tiles, with 3 threads in 37-pixel tiles and frames in reverse order; the results must match
# exactly (nprfx diff --fail 0 --hardfail 0).
set -u
NPRFX=$1; SRC=$2; W=$3
rm -rf "$W"; mkdir -p "$W"
passes=0; fails=0
. "$SRC/tests/lib/flow.sh"
for g in "$SRC"/tests/graphs/*.json; do
  needs_missing_flow "$NPRFX" "$g" && { echo "skipped $(basename "$g"): no optical flow in this build"; continue; }
  name=$(basename "$g" .json)
  "$NPRFX" run "$g" --output-dir "$W/a" --threads 1 --quiet || { echo "FAIL: $name (1 thread)"; fails=$((fails+1)); continue; }
  "$NPRFX" run "$g" --output-dir "$W/b" --threads 4 --tile 16 --quiet || { echo "FAIL: $name (4 threads)"; fails=$((fails+1)); continue; }
  frames=$(grep -o '"frames": *"[0-9]*-[0-9]*"' "$g" | grep -o '[0-9]*-[0-9]*')
  rev=$(echo "$frames" | awk -F- '{print $2 "-" $1}')
  "$NPRFX" run "$g" --output-dir "$W/c" --threads 3 --tile 37 ${rev:+--frames $rev} --quiet || { echo "FAIL: $name (reverse)"; fails=$((fails+1)); continue; }
done
for f in "$W"/a/golden/*.exr; do
  b="$W/b/golden/$(basename "$f")"; c="$W/c/golden/$(basename "$f")"
  for other in "$b" "$c"; do
    if "$NPRFX" diff "$f" "$other" --fail 0 --hardfail 0 --warn 0 >/dev/null 2>&1; then passes=$((passes+1))
    else echo "FAIL: $(basename "$f") differs between runs ($other)"; "$NPRFX" diff "$f" "$other" --fail 0; fails=$((fails+1)); fi
  done
done
echo "$passes passed, $fails failed"
[ $fails -eq 0 ] && [ $passes -gt 0 ]
