#!/usr/bin/env bash
# A graph's design width (docs/design.md §3.6): on a plate twice the design width, params in
# pixels are doubled and areas quadrupled, and what nodes derive from pixel positions
# (gabor-splat's frequency) follows: the render is bit-identical to the same graph without a
# design width and its params doubled by hand. By strips of rows too (the filters' margins
# follow the scaled params). Bad widths are refused with a message naming them. The synth
# lights: point has HDR highlights, lowkey is dark, sun is the default's beauty. A size scaled
# below its param's range takes the range's end.
set -u
NPRFX=$1; SRC=$2; W=$3
rm -rf "$W"; mkdir -p "$W"; cd "$W" || exit 1
passes=0; fails=0
pass() { passes=$((passes+1)); }
fail() { echo "FAIL: $*"; fails=$((fails+1)); }

# graph NAME DESIGN RADIUS FREQ MRADIUS WIDTH: gabor-splat, lines and morphology on a 256x192 plate
graph() {
  local design=""
  [ "$2" != none ] && design="\"design_width\": $2,"
  cat > "$1.json" <<G
{"frames": "1", $design "nodes": {
  "plate": {"node": "synth", "scene": "orbit", "size": "256x192"},
  "dots": {"node": "gabor-splat", "inputs": {"anchor": "plate:Pref.X,Pref.Y,Pref.Z", "depth": "plate:Z", "id": "plate:id"},
           "params": {"radius": $3, "frequency": $4, "isotropic": true}},
  "grow": {"node": "morphology", "inputs": {"image": "dots"}, "params": {"radius": $5}},
  "ink": {"node": "lines", "inputs": {"id": "plate:id", "depth": "plate:Z", "normal": "plate:N.X,N.Y,N.Z"},
          "params": {"width": $6}},
  "w1": {"node": "write", "inputs": {"image": "grow"}, "path": "$1/grow.####.exr"},
  "w2": {"node": "write", "inputs": {"image": "ink"}, "path": "$1/ink.####.exr"}}}
G
}
graph designed 128 8 0.1 3 1.5
graph by_hand none 16 0.05 6 3
graph unscaled none 8 0.1 3 1.5
for g in designed by_hand unscaled; do
  "$NPRFX" run $g.json -q > $g.log 2>&1 || fail "$g: $(cat $g.log)"
done
# by strips: a chain of EXR read and morphology renders by rows; its margin must be the scaled
# radius (6 px), not the graph's (3)
"$NPRFX" synth orbit --size 256x192 -o plate.exr > /dev/null || fail "synth plate"
cat > strip.json <<G
{"frames": "1", "design_width": 128, "nodes": {
  "plate": {"node": "read", "path": "plate.exr"},
  "grow": {"node": "morphology", "inputs": {"image": "plate:diffuse"}, "params": {"radius": 3}},
  "w": {"node": "write", "inputs": {"image": "grow"}, "path": "strip/grow.####.exr"}}}
G
"$NPRFX" run strip.json -q --strip-rows 8 --stats --output-dir strips > strips.log 2>&1 ||
  fail "strips: $(cat strips.log)"
grep -q "strip" strips.log || fail "the strip graph did not render by strips: $(cat strips.log)"
"$NPRFX" run strip.json -q --strip-rows -1 --output-dir whole > whole.log 2>&1 ||
  fail "whole: $(cat whole.log)"
"$NPRFX" run unscaled.json -q --design-width 256 --output-dir off > off.log 2>&1 ||
  fail "--design-width 256: $(cat off.log)"
"$NPRFX" run designed.json -q --design-width off --output-dir off2 > off2.log 2>&1 ||
  fail "--design-width off: $(cat off2.log)"
same() { "$NPRFX" diff "$1" "$2" --fail 0 --failpercent 0 > d.txt 2>&1; }
for f in grow ink; do
  same designed/$f.0001.exr by_hand/$f.0001.exr && pass ||
    { fail "$f: design width 128 on a 256-wide plate differs from the params doubled"; cat d.txt; }
  same off/unscaled/$f.0001.exr unscaled/$f.0001.exr && pass ||
    fail "$f: --design-width equal to the plate's width changed the render"
  same off2/designed/$f.0001.exr unscaled/$f.0001.exr && pass ||
    fail "$f: --design-width off did not give the params in the plate's pixels"
  same designed/$f.0001.exr unscaled/$f.0001.exr && fail "$f: the design width changed nothing" || pass
done

same strips/strip/grow.0001.exr whole/strip/grow.0001.exr && pass ||
  { fail "morphology by strips of 8 rows differs from the whole frame"; cat d.txt; }

# a size at its range's end stays valid on a proxy: paper's thread 2 and 1 (minimum 1) designed for
# 1024 both render on the 256-wide plate as thread 1, the minimum (they were refused as 0.5, 0.25)
paper() { # NAME DESIGN THREAD
  printf '{"frames": "1", "design_width": %s, "nodes": {"plate": {"node": "synth", "scene": "orbit", "size": "256x192"}, "p": {"node": "paper", "inputs": {"image": "plate:beauty"}, "params": {"thread": %s}}, "w": {"node": "write", "inputs": {"image": "p"}, "path": "%s/p.####.exr"}}}\n' "$2" "$3" "$1" > "$1.json"
  "$NPRFX" run "$1.json" -q > "$1.log" 2>&1 || fail "$1: $(cat "$1.log")"
}
paper paper_proxy 1024 2
paper paper_min 1024 1
same paper_proxy/p.0001.exr paper_min/p.0001.exr && pass ||
  { fail "paper threads 2 and 1 designed at 1024 on a 256 plate differ (both are its minimum)"; cat d.txt; }

# refusals
expect_error() { # NAME PATTERN -- command
  local name=$1 pattern=$2; shift 3
  "$@" > "$name.out" 2> "$name.err"; local st=$?
  if [ $st -ne 2 ] || ! grep -qF -- "$pattern" "$name.err"; then
    fail "$name: exit $st, stderr: $(cat "$name.err") (want '$pattern')"
  else pass; fi
}
sed 's/"design_width": 128/"design_width": "wide"/' designed.json > bad1.json
expect_error bad_type "top-level entry 'design_width' must be the plate width" -- "$NPRFX" run bad1.json -q
sed 's/"design_width": 128/"design_width": 0/' designed.json > bad2.json
expect_error zero "top-level entry 'design_width'" -- "$NPRFX" run bad2.json -q
sed 's/"design_width": 128/"design_width": 128, "design_width": 256/' designed.json > bad3.json
expect_error twice "top-level entry 'design_width' is given twice" -- "$NPRFX" run bad3.json -q
expect_error cli_word "--design-width 'wide'" -- "$NPRFX" run designed.json -q --design-width wide
expect_error cli_negative "--design-width '-5'" -- "$NPRFX" run designed.json -q --design-width -5

# synth lights
stat() { oiiotool "$1" --ch R,G,B --printstats 2>/dev/null | awk -v k="$2" '$0 ~ "Stats " k {print $3}'; }
"$NPRFX" synth orbit --size 128x96 -o default.exr > /dev/null &&
  "$NPRFX" synth orbit --size 128x96 --light sun -o sun.exr > /dev/null &&
  "$NPRFX" synth orbit --size 128x96 --light point -o point.exr > /dev/null &&
  "$NPRFX" synth orbit --size 128x96 --light lowkey -o lowkey.exr > /dev/null || fail "synth --light"
same default.exr sun.exr && pass || fail "--light sun differs from the default"
max=$(stat point.exr Max); awk -v m="$max" 'BEGIN { exit !(m > 10) }' && pass ||
  fail "--light point: beauty's red max $max, want HDR highlights above 10"
avg=$(stat lowkey.exr Avg); awk -v m="$avg" 'BEGIN { exit !(m < 0.05) }' && pass ||
  fail "--light lowkey: mean red $avg, want below 0.05"
expect_error bad_light "--light must be sun, point or lowkey, not 'moon'" -- \
  "$NPRFX" synth orbit --light moon -o x.exr

echo "$passes passed, $fails failed"
[ $fails -eq 0 ]
