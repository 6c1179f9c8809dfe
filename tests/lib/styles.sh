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
