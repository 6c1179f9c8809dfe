#!/usr/bin/env bash
# Pixel-diff regression: every tests/graphs/*.json is rendered and each image it writes is
# compared with the file of the same name in tests/golden/ (docs/design.md §4 thresholds for
# deterministic float outputs: fail 1e-5, failpercent 0, hardfail 1e-4). A failure leaves a
# scaled difference image beside the output.
# Regenerate the golden files (and explain why in the commit): tests/golden/regen.sh BUILD/nprfx
set -u
NPRFX=$1; SRC=$2; W=$3
rm -rf "$W"; mkdir -p "$W"
passes=0; fails=0
. "$SRC/tests/lib/flow.sh"
for g in "$SRC"/tests/graphs/*.json; do
  if needs_missing_flow "$NPRFX" "$g"; then
    echo "skipped $(basename "$g"): no optical flow in this build"
    # its goldens too: the names before the frame number of its write paths
    skipped="${skipped:-} $(grep -o '"path": *"golden/[^"#]*' "$g" | sed 's|.*golden/||; s|\.$||' | tr '\n' ' ')"
    continue
  fi
  name=$(basename "$g" .json)
  if ! "$NPRFX" run "$g" --output-dir "$W" --quiet; then
    echo "FAIL: $name did not render"; fails=$((fails+1)); continue
  fi
done
# every golden file must be produced, and every produced file must have a golden
for gold in "$SRC"/tests/golden/*.exr; do
  f="$W/golden/$(basename "$gold")"
  stem=$(basename "$gold"); stem=${stem%%.[0-9]*}
  case " ${skipped:-} " in *" $stem "*) continue ;; esac
  if [ ! -f "$f" ]; then echo "FAIL: $(basename "$gold") was not produced"; fails=$((fails+1)); continue; fi
  if "$NPRFX" diff "$gold" "$f" --fail 1e-5 --failpercent 0 --hardfail 1e-4 --warn 1e-5 \
       --out "${f%.exr}.diff.exr" --scale 1000 > "${f%.exr}.diff.txt" 2>&1; then
    passes=$((passes+1))
  else
    echo "FAIL: $(basename "$gold") differs (diff image ${f%.exr}.diff.exr):"; cat "${f%.exr}.diff.txt"
    fails=$((fails+1))
  fi
done
for f in "$W"/golden/*.exr; do
  case "$f" in *.diff.exr) continue;; esac
  [ -f "$SRC/tests/golden/$(basename "$f")" ] || { echo "FAIL: no golden file for $(basename "$f") (run tests/golden/regen.sh)"; fails=$((fails+1)); }
done
echo "$passes passed, $fails failed"
[ $fails -eq 0 ] && [ $passes -gt 0 ]
