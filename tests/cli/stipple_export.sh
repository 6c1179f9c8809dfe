#!/usr/bin/env bash
# The stipple node's vector export through the runner (its `export` param is a per-frame
# NPRFX_PARAM_EXPORT path; the runner writes the node's export_text through a temporary name):
# .csv gives the header x,y,radius,tone,sample,object and one row per dot, and the dots' summed
# area matches the ink coverage the node drew; .svg gives the frame size as viewBox and one
# <circle> per dot at the CSV's positions; the export does not depend on tiles or threads; any
# other extension is a clear error.
#
# usage: bash stipple_export.sh NPRFX_BINARY SOURCE_DIR WORK_DIR
set -u
NPRFX=$1; SRC=$2; W=$3
rm -rf "$W"; mkdir -p "$W"; cd "$W"
passes=0; fails=0
pass() { passes=$((passes+1)); }
fail() { echo "FAIL: $*"; fails=$((fails+1)); }

# A light tone (0.3 diffuse + 0.7 white), so that few dots overlap and the union of the discs
# the node draws is close to the sum of their areas.
cat > export.json <<'G'
{"frames": "1-2", "nodes": {
 "plate": {"node": "synth", "scene": "orbit", "size": "128x96"},
 "light": {"node": "blend", "inputs": {"base": "plate:diffuse", "layer": "plate:coverage"},
           "params": {"mode": "alphablend", "opacity": 0.7}},
 "dots": {"node": "stipple", "inputs": {"tone": "light", "uv": "plate:UV.U,UV.V", "id": "plate:id"},
          "params": {"size": 2, "tile": 8, "coverage": true, "export": "out/dots.####.csv"}},
 "w": {"node": "write", "inputs": {"image": "dots"}, "path": "out/dots.####.exr"}}}
G

if ! "$NPRFX" run export.json --quiet > run.log 2>&1; then
  fail "the CSV graph did not run:"; cat run.log
fi
for f in 0001 0002; do
  csv=out/dots.$f.csv
  if [ ! -s "$csv" ]; then fail "no $csv"; continue; fi
  [ "$(head -n 1 "$csv")" = "x,y,radius,tone,sample,object" ] && pass || fail "$csv header is '$(head -n 1 "$csv")'"
  rows=$(($(wc -l < "$csv") - 1))
  [ "$rows" -gt 200 ] && pass || fail "$csv has only $rows dots"
  # every row: six fields, inside the frame (corner coordinates), radius > 0, tone in (0, 1]
  bad=$(awk -F, 'NR > 1 && (NF != 6 || $1 < 0 || $1 > 128 || $2 < 0 || $2 > 96 || $3 <= 0 || $4 <= 0 || $4 > 1 || $5 < 0 || $6 < 1 || $6 > 3)' "$csv" | wc -l)
  [ "$bad" -eq 0 ] && pass || fail "$csv has $bad malformed rows"
  # sum of pi r^2 tone over the rows against the ink coverage of the EXR (its 5th channel)
  area=$(awk -F, 'NR > 1 { s += 3.14159265358979 * $3 * $3 * $4 } END { printf "%.3f", s }' "$csv")
  avg=$(oiiotool out/dots.$f.exr --ch coverage --printstats | sed -n 's/.*Stats Avg: *\([0-9.e+-]*\).*/\1/p')
  if [ -z "$avg" ]; then fail "cannot read the coverage of out/dots.$f.exr"; continue; fi
  ratio=$(awk -v a="$area" -v c="$avg" 'BEGIN { printf "%.4f", c * 128 * 96 / a }')
  echo "frame $f: $rows dots, summed disc area $area px^2, ink coverage / summed area = $ratio"
  # the union of the discs is at most their sum (overlaps), and close to it at this tone
  awk -v r="$ratio" 'BEGIN { exit !(r >= 0.95 && r <= 1.0001) }' && pass || fail "frame $f: coverage / area = $ratio, want [0.95, 1]"
done
cmp -s out/dots.0001.csv out/dots.0002.csv && fail "frames 1 and 2 exported the same dots" || pass
# written through a temporary name: nothing else is left in out/
extra=$(ls out | grep -v '^dots\.000[12]\.\(csv\|exr\)$')
[ -z "$extra" ] && pass || fail "unexpected files in out/: $extra"

# tiles and threads change nothing
"$NPRFX" run export.json --quiet --threads 3 --tile 16 --output-dir tiled > run.log 2>&1 || { fail "tiled run failed"; cat run.log; }
cmp -s out/dots.0001.csv tiled/out/dots.0001.csv && cmp -s out/dots.0002.csv tiled/out/dots.0002.csv && pass || fail "the CSV depends on tiles or threads"

# SVG: same dots, frame-size viewBox, one <circle per row at the CSV's positions
if "$NPRFX" run export.json --quiet --frames 1 --set dots.export=svg/dots.####.svg > run.log 2>&1; then
  svg=svg/dots.0001.svg
  if [ -s "$svg" ]; then
    grep -q 'viewBox="0 0 128 96"' "$svg" && pass || fail "$svg: no viewBox=\"0 0 128 96\": $(grep -o 'viewBox="[^"]*"' "$svg")"
    grep -q '</svg>' "$svg" && pass || fail "$svg is not closed"
    circles=$(grep -o '<circle' "$svg" | wc -l)
    rows=$(($(wc -l < out/dots.0001.csv) - 1))
    [ "$circles" -eq "$rows" ] && pass || fail "$svg has $circles circles, the CSV $rows rows"
    sed -n 's/.*<circle cx="\([^"]*\)" cy="\([^"]*\)".*/\1 \2/p' "$svg" > svg_xy.txt
    awk -F, 'NR > 1 { printf "%.3f %.3f\n", $1, $2 }' out/dots.0001.csv > csv_xy.txt
    far=$(paste -d' ' svg_xy.txt csv_xy.txt | awk '{ d = ($1 - $3) ^ 2 + ($2 - $4) ^ 2; if (d > 1e-5) n++ } END { print n + 0 }')
    [ "$far" -eq 0 ] && [ -s svg_xy.txt ] && pass || fail "$far SVG circles are not at their CSV positions"
  else fail "no $svg"; fi
else
  fail "the SVG graph did not run:"; cat run.log
fi
# the extension is case-insensitive
"$NPRFX" run export.json --quiet --frames 1 --set dots.export=up/dots.####.CSV > run.log 2>&1 && cmp -s up/dots.0001.CSV out/dots.0001.csv && pass || { fail ".CSV was not written as CSV"; cat run.log; }

# anything else is an error that names the node, the path and the extension
for bad in png/dots.####.png:"unknown extension '.png'" noext/dots_####:"has no extension"; do
  path=${bad%%:*}; want=${bad#*:}
  if "$NPRFX" run export.json --quiet --frames 1 --set "dots.export=$path" > run.log 2>&1; then
    fail "export to $path succeeded"
  else
    grep -qF "$want" run.log && grep -qF "node 'dots'" run.log && grep -qF ".csv" run.log && grep -qF ".svg" run.log && pass || { fail "the error for $path is unclear:"; cat run.log; }
  fi
  [ -z "$(ls "${path%%/*}" 2>/dev/null | grep -v '\.exr$')" ] && pass || fail "a failed export left files in ${path%%/*}/"
done

echo "$passes passed, $fails failed"
[ $fails -eq 0 ]
