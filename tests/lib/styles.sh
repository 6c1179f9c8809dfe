# Sourced by tests/cli/styles.sh and tests/golden/regen.sh: how the style graphs are rendered for
# their golden files, so that the test and the regeneration cannot drift apart.
#
# A style graph is a sample graph (samples/graphs/*.json) with a node named "look" (the styled
# image), "matte" (the object coverage), "paper" (the background) and a read node "plate".
# For the goldens each one runs, with only its read path changed, on the synthetic 'dolly' scene
# written in Blender's layout (a torus on an empty background: nprfx synth --layout blender).

STYLE_PLATE_SIZE=192x108
STYLE_PLATE_FRAMES=1-8
STYLE_GOLDEN_FRAMES=2-3

# The style graphs under source dir $1, one path per line: those with "look" and "matte" (the
# footage graphs, samples/graphs/footage_*.json, have no matte: footage has no depth or ids, and
# they are tested on footage by tests/cli/footage.sh).
style_graphs() {
  grep -l '"look": *{' "$1"/samples/graphs/*.json | xargs grep -l '"matte": *{'
}

# style_plates NPRFX DIR: the synthetic plates, DIR/dolly.####.exr.
style_plates() {
  "$1" synth dolly --layout blender --size "$STYLE_PLATE_SIZE" --frames "$STYLE_PLATE_FRAMES" \
    -o "$2/dolly.####.exr" >/dev/null
}

# style_measure_plates NPRFX DIR: larger synthetic plates for nprfx measure (background, tone
# curve), where objects are big enough for their interiors to count: DIR/dolly.####.exr.
STYLE_MEASURE_SIZE=512x288
STYLE_MEASURE_FRAMES=1-4
style_measure_plates() {
  "$1" synth dolly --layout blender --size "$STYLE_MEASURE_SIZE" --frames "$STYLE_MEASURE_FRAMES" \
    -o "$2/dolly.####.exr" >/dev/null
}

# style_render NPRFX GRAPH PLATES_DIR OUT_DIR: the golden frames of one style graph.
style_render() {
  "$1" run "$2" --set "plate.path=$3/dolly.####.exr" --shot "$STYLE_PLATE_FRAMES" \
    --frames "$STYLE_GOLDEN_FRAMES" --output-dir "$4" --quiet
}

# style_look NPRFX GRAPH PLATE OUT [run options]: frame 2 of GRAPH's look (the image its write
# node of "look" writes) on the plates PLATE (a path with ####, frames 1-2 as the shot), moved
# to OUT.exr; the run's messages in OUT.log. On failure it prints why and returns 1.
style_look() {
  local nprfx=$1 g=$2 plate=$3 out=$4 f
  shift 4
  rm -rf "run_$out"
  "$nprfx" run "$g" --set "plate.path=$plate" --shot 1-2 --frames 2 --output-dir "run_$out" \
    --quiet "$@" > "$out.log" 2>&1 || { tail -3 "$out.log"; return 1; }
  f=run_$out/$(python3 -c 'import json, sys
for n in json.load(open(sys.argv[1]))["nodes"].values():
    if n.get("node") == "write" and n.get("inputs", {}).get("image") == "look":
        print(n["path"].replace("####", "0002")); break' "$g")
  [ -f "$f" ] || { echo "wrote no $f"; return 1; }
  mv "$f" "$out.exr"
  rm -rf "run_$out"
}

# style_lum IMG OUT [GRID]: the luminance (Rec. 709 weights) of IMG's R, G, B, optionally
# averaged into GRID blocks (oiiotool's box resize), as a float image
style_lum() {
  local resize=()
  [ -n "${3:-}" ] && resize=(--resize:filter=box "$3")
  oiiotool "$1" --ch R,G,B --chsum:weight=.2126,.7152,.0722 "${resize[@]}" -d float -o "$2"
}

# style_avg IMG: the mean of its one channel
style_avg() { oiiotool "$1" --printstats 2>/dev/null | awk '/Stats Avg/ { print $3; exit }'; }
