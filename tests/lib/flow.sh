# Sourced by the CLI tests that render graphs: the flow node needs an optical flow provider
# (OpenCV, common/flow_opencv.cpp), which a build without OpenCV lacks. Such a build skips what
# needs it instead of failing (.ci/setup installs OpenCV, so CI runs everything).

# flow_missing NPRFX: true when this nprfx has no optical flow provider.
flow_missing() {
  "$1" --version 2>/dev/null | grep -q "^optical flow: none"
}

# needs_missing_flow NPRFX GRAPH: true when GRAPH uses the flow node and NPRFX has no provider.
needs_missing_flow() {
  grep -q '"node": *"flow"' "$2" && flow_missing "$1"
}
