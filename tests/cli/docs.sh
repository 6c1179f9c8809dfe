#!/usr/bin/env bash
# The node reference in docs/nodes.md is generated from the descriptors: it must match what the
# binary prints (regenerate with: build/nprfx docs -o docs/nodes.md). Also checks that `list` and
# `help` are generated for every node and that help documents every param.
set -u
NPRFX=$1; SRC=$2; W=$3
rm -rf "$W"; mkdir -p "$W"
passes=0; fails=0
ok() { passes=$((passes+1)); }
bad() { fails=$((fails+1)); echo "FAIL: $*"; }
"$NPRFX" docs -o "$W/nodes.md" || bad "nprfx docs failed"
if cmp -s "$W/nodes.md" "$SRC/docs/nodes.md"; then ok; else
  bad "docs/nodes.md is out of date: run build/nprfx docs -o docs/nodes.md"; diff "$SRC/docs/nodes.md" "$W/nodes.md" | head -20; fi
for id in $("$NPRFX" list | awk '$2 != "I/O" {print $1}'); do
  "$NPRFX" help "$id" > "$W/help.txt" || { bad "help $id"; continue; }
  grep -q "^Params:" "$W/help.txt" && ok || bad "help $id has no Params section"
done
"$NPRFX" list | grep -q '^threshold-map ' && ok || bad "list lacks threshold-map"
"$NPRFX" list | grep -q '^blend ' && ok || bad "list lacks blend"
# every blend mode is documented with its formula
"$NPRFX" help blend > "$W/blend.txt"
for m in alphablend overlay overlayalpha multiply screen pigment; do
  grep -qE "^ +$m +[^ ].*" "$W/blend.txt" && ok || bad "help blend does not give the formula of $m"
done
"$NPRFX" help no-such-node 2> "$W/err.txt"; [ $? -eq 2 ] && grep -q "unknown node 'no-such-node'" "$W/err.txt" && ok || bad "help of an unknown node"
echo "$passes passed, $fails failed"
[ $fails -eq 0 ]
