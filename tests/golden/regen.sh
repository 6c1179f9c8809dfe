#!/usr/bin/env bash
# Regenerate tests/golden/ from tests/graphs/*.json with the given nprfx binary:
#   tests/golden/regen.sh build/nprfx
# Only after checking that the change in output is intended; say why in the commit message.
set -euo pipefail
NPRFX=${1:?usage: tests/golden/regen.sh PATH/TO/nprfx}
here=$(cd "$(dirname "$0")" && pwd)
rm -f "$here"/*.exr
for g in "$here"/../graphs/*.json; do
  "$NPRFX" run "$g" --output-dir "$here/.." --quiet
done
ls "$here"/*.exr | wc -l | xargs echo "golden files:"
