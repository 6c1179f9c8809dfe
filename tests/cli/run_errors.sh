#!/usr/bin/env bash
# Bad input gets one clear message naming the file, node, input, channel or param, a non-zero
# exit, and nothing partially written.
set -u
NPRFX=$1; SRC=$2; W=$3
rm -rf "$W"; mkdir -p "$W"; cd "$W"
fails=0; passes=0

# expect CODE PATTERN -- command...: exit status must be CODE (or non-zero for "nz"),
# stderr must contain PATTERN.
expect() {
  local code=$1 pattern=$2; shift 3
  "$@" >out.txt 2>err.txt; local st=$?
  if { [ "$code" = nz ] && [ $st -ne 0 ]; } || [ "$st" = "$code" ]; then
    if grep -qF -- "$pattern" err.txt; then passes=$((passes+1)); return; fi
  fi
  fails=$((fails+1))
  echo "FAIL: '$*' exited $st (want $code), stderr:"; cat err.txt; echo "(wanted: $pattern)"
}

graph() { # graph NAME BODY: write NAME.json with a synth plate and BODY nodes
  printf '{"frames": "1-3", "nodes": {"plate": {"node": "synth", "scene": "orbit", "size": "32x24"}, %s}}\n' "$2" > "$1.json"
}

graph missing_file '"r": {"node": "read", "path": "nowhere/plate.####.exr"}, "w": {"node": "write", "inputs": {"image": "r"}, "path": "o/x.####.exr"}'
expect nz "nowhere/plate.0001.exr" -- "$NPRFX" run missing_file.json

graph missing_channel '"b": {"node": "blend", "inputs": {"base": "plate", "layer": "plate:Nope.Z"}}, "w": {"node": "write", "inputs": {"image": "b"}, "path": "o/x.####.exr"}'
expect nz "'Nope.Z' is not a channel in 'plate'" -- "$NPRFX" run missing_channel.json

graph wrong_count '"b": {"node": "blend", "inputs": {"base": "plate", "layer": "plate", "alpha": "plate:UV"}}, "w": {"node": "write", "inputs": {"image": "b"}, "path": "o/x.####.exr"}'
expect nz "input 'alpha' needs 1 channel, 'plate:UV' gives 2" -- "$NPRFX" run wrong_count.json

graph wrong_size '"small": {"node": "synth", "scene": "orbit", "size": "16x12"}, "b": {"node": "blend", "inputs": {"base": "plate", "layer": "small"}}, "w": {"node": "write", "inputs": {"image": "b"}, "path": "o/x.####.exr"}'
expect nz "input 'layer' is 16x12 but input 'base' is 32x24" -- "$NPRFX" run wrong_size.json

# Same size, other origin: the message names the data windows, not two equal sizes.
if command -v oiiotool >/dev/null; then
  oiiotool --pattern constant:color=0.5,0.5,0.5,1 64x48 4 -d float --crop 20x15+10+0 -o shifted.0001.exr \
           --pattern constant:color=0.5,0.5,0.5,1 64x48 4 -d float --crop 20x15+0+0 -o home.0001.exr
  printf '{"frames": "1", "nodes": {"s": {"node": "read", "path": "shifted.####.exr"}, "h": {"node": "read", "path": "home.####.exr"}, "b": {"node": "blend", "inputs": {"base": "h", "layer": "s"}}, "w": {"node": "write", "inputs": {"image": "b"}, "path": "o/x.####.exr"}}}\n' > wrong_origin.json
  expect nz "input 'layer' has data window 20x15+10+0 but input 'base' has 20x15+0+0" -- "$NPRFX" run wrong_origin.json
fi

# Hours of work are announced before the first frame: a million frames, a huge footprint. The
# plate is missing, so frame 1 fails at once after the warning and nothing renders for hours.
printf '{"frames": "1-1000000", "nodes": {"r": {"node": "read", "path": "nowhere/p.####.exr"}, "m": {"node": "morphology", "inputs": {"image": "r"}, "params": {"radius": 200}}, "w": {"node": "write", "inputs": {"image": "m"}, "path": "o/x.####.exr"}}}\n' > hours.json
expect nz "1000000 frames: at one second a frame that is 278 hours" -- "$NPRFX" run hours.json
expect nz "node 'm' (morphology) reads up to 160801 pixels (radius 200) for every pixel" -- "$NPRFX" run hours.json

graph unknown_node '"b": {"node": "blurp", "inputs": {}}, "w": {"node": "write", "inputs": {"image": "b"}, "path": "o/x.####.exr"}'
expect 2 "unknown node type 'blurp'" -- "$NPRFX" run unknown_node.json

graph unknown_param '"b": {"node": "blend", "inputs": {"base": "plate", "layer": "plate"}, "params": {"bogus": 1}}, "w": {"node": "write", "inputs": {"image": "b"}, "path": "o/x.####.exr"}'
expect 2 "blend has no param 'bogus'" -- "$NPRFX" run unknown_param.json

graph ok '"b": {"node": "blend", "inputs": {"base": "plate", "layer": "plate:diffuse"}}, "w": {"node": "write", "inputs": {"image": "b"}, "path": "o/ok.####.exr"}'
expect 2 "blend.opacity: 7 is outside the range" -- "$NPRFX" run ok.json --set b.opacity=7
expect 2 "'sideways' is not one of: alphablend" -- "$NPRFX" run ok.json --set b.mode=sideways
expect 2 "the graph has no node 'nob'" -- "$NPRFX" run ok.json --set nob.opacity=1
expect 2 "frame 9 is outside the graph's frames 1-3" -- "$NPRFX" run ok.json --frames 9
expect 2 "cannot open graph file 'absent.json'" -- "$NPRFX" run absent.json

# Frames at the ends of int are refused with the range nprfx renders; its own ends render, a
# temporal node reaching back and a time offset reaching ahead of them included (run under
# UBSan, an overflow in the frame arithmetic stops the process).
edge() { # edge NAME FRAMES OFFSET
  printf '{"frames": "%s", "nodes": {"plate": {"node": "synth", "scene": "orbit", "size": "32x24"}, "n": {"node": "coherent-noise", "inputs": {"depth": "plate", "motion_prev": "plate"}}, "t": {"node": "time-offset", "inputs": {"image": "n"}, "params": {"offset": %s}}, "w": {"node": "write", "inputs": {"image": "t"}, "path": "o/%s.#.exr"}}}\n' "$2" "$3" "$1" > "$1.json"
}
edge top 2147483647 0
expect 2 "frame 2147483647 in '2147483647' is outside the frames nprfx renders (-999999999 to 999999999)" -- "$NPRFX" run top.json
edge bottom -2147483648 0
expect 2 "frame -2147483648 in '-2147483648' is outside the frames nprfx renders" -- "$NPRFX" run bottom.json
edge hi 999999998-999999999 100000
expect 0 "" -- "$NPRFX" run hi.json
[ -f o/hi.999999999.exr ] && passes=$((passes+1)) || { fails=$((fails+1)); echo "FAIL: no o/hi.999999999.exr"; }
edge lo -999999999--999999998 -100000
expect 0 "" -- "$NPRFX" run lo.json
[ -f o/lo.-999999998.exr ] && passes=$((passes+1)) || { fails=$((fails+1)); echo "FAIL: no o/lo.-999999998.exr"; }
expect 2 "outside the frames nprfx renders" -- "$NPRFX" run hi.json --frames 1000000000

graph unconnected '"b": {"node": "blend", "inputs": {"base": "plate"}}, "w": {"node": "write", "inputs": {"image": "b"}, "path": "o/x.####.exr"}'
expect 2 "node 'b': required input 'layer' is not connected" -- "$NPRFX" run unconnected.json

graph dangling '"b": {"node": "blend", "inputs": {"base": "plate", "layer": "ghost"}}, "w": {"node": "write", "inputs": {"image": "b"}, "path": "o/x.####.exr"}'
expect 2 "refers to 'ghost', which is not a node" -- "$NPRFX" run dangling.json

printf '{"nodes": {"a": {"node": "synth",\n "scene": }}}\n' > malformed.json
expect 2 "malformed JSON near line 2, column 11" -- "$NPRFX" run malformed.json
# Columns count characters, not UTF-8 bytes: the error is at the "2" after the "1".
printf '{"nodes": {"a": {"node": "synth",\n  "\303\251": 1 2}}}\n' > malformed_utf8.json
expect 2 "malformed JSON near line 2, column 10" -- "$NPRFX" run malformed_utf8.json

# The JSON reader keeps both of two equal keys: a name given twice is an error, not a hidden node.
graph duplicate '"b": {"node": "blend", "inputs": {"base": "plate", "layer": "plate"}}, "b": {"node": "blend", "inputs": {"base": "plate", "layer": "plate"}}, "w": {"node": "write", "inputs": {"image": "b"}, "path": "o/x.####.exr"}'
expect 2 "duplicate.json: node name 'b' is given twice" -- "$NPRFX" run duplicate.json

graph cycle '"a": {"node": "blend", "inputs": {"base": "plate", "layer": "b"}}, "b": {"node": "blend", "inputs": {"base": "plate", "layer": "a"}}, "w": {"node": "write", "inputs": {"image": "b"}, "path": "o/x.####.exr"}'
expect 2 "cycle.json: the graph has a cycle: a -> b -> a" -- "$NPRFX" run cycle.json
graph self_cycle '"a": {"node": "blend", "inputs": {"base": "plate", "layer": "a"}}, "w": {"node": "write", "inputs": {"image": "a"}, "path": "o/x.####.exr"}'
expect 2 "the graph has a cycle: a -> a" -- "$NPRFX" run self_cycle.json

# A failed frame leaves the frames before it whole and no temporary file behind.
mkdir -p seq
"$NPRFX" synth orbit --frames 1-2 --size 32x24 -o seq/p.####.exr >/dev/null 2>&1
cat > partial.json <<'G'
{"frames": "1-3", "nodes": {"r": {"node": "read", "path": "seq/p.####.exr"},
 "w": {"node": "write", "inputs": {"image": "r:R,G,B,A"}, "path": "o/p.####.exr"}}}
G
expect 1 "seq/p.0003.exr" -- "$NPRFX" run partial.json
if [ -f o/p.0001.exr ] && [ -f o/p.0002.exr ] && [ ! -e o/p.0003.exr ] &&
   [ -z "$(find o -name '*.tmp*' -o -name '.*' -type f)" ]; then passes=$((passes+1))
else fails=$((fails+1)); echo "FAIL: partial sequence state:"; ls -la o; fi

# Inputs are never overwritten, even by a graph that writes onto its own plates.
cat > overwrite.json <<'G'
{"frames": "1", "nodes": {"r": {"node": "read", "path": "seq/p.####.exr"},
 "w": {"node": "write", "inputs": {"image": "r"}, "path": "seq/p.####.exr"}}}
G
sum=$(md5sum seq/p.0001.exr)
expect nz "refusing to overwrite" -- "$NPRFX" run overwrite.json
[ "$(md5sum seq/p.0001.exr)" = "$sum" ] && passes=$((passes+1)) || { fails=$((fails+1)); echo "FAIL: input changed"; }

echo "$passes passed, $fails failed"
[ $fails -eq 0 ]
