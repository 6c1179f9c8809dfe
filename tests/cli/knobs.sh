#!/usr/bin/env bash
# A graph's knobs (docs/design.md §3.6): every shipped style graph lists its params worth turning
# and `nprfx help GRAPH.json` shows them with values, ranges and the graph's words (and the look
# plug-in the graph is in hosts, with its clips and params); a knob that
# names no such param, or a malformed entry, is refused at load with its reason; --set with a *
# sets every matching node that has the param, the same as setting each.
set -u
NPRFX=$1; SRC=$2; W=$3
. "$SRC/tests/cli/lib/check.sh"
work_in "$W"

# Every style graph (a read node, params set for 1280 wide: the looks, not the figures and
# sample-only graphs tuned at 320) lists knobs, all valid, shown by help.
n=0
for g in "$SRC"/samples/graphs/*.json; do
    grep -q '"node": "read"' "$g" && grep -q '"design_width": 1280' "$g" || continue
    expect_rc 0 "$NPRFX" help "$g"
    k=$(sed -n '/^Knobs/,$p' last.out | grep -c '^  [^ ]')
    [ "$k" -ge 5 ] || { cat last.out >&2; fail "$g lists $k knobs (a style lists its params worth turning)"; }
    n=$((n + 1))
done
[ "$n" -ge 15 ] || fail "only $n style graphs found"
expect_rc 0 "$NPRFX" help "$SRC/samples/graphs/cross_hatching.json"
has last.out "strokes*.frequency"
has last.out "(2 nodes)"
has last.out "stroke spacing"
has last.out "Shot: frames 1-24; params set for plates 1280 pixels wide"
# the same graph as one effect in hosts: its plug-in, clips and params (look_desc.h)
has last.out "In compositing hosts: NPR/Looks > Cross hatching (org.nprfx.look.CrossHatching)"
has last.out "clips: Source"
has last.out " strokes_frequency"
# in hosts with layers: the renderer choice, Find AOV Layers, AOV Layers and a menu per AOV
has last.out "with layers also: renderer findLayers aovLayers layer_beauty layer_albedo layer_depth layer_normal layer_position layer_rest layer_uv layer_id"

# Refusals, each with its reason.
graph() { # KNOBS_JSON: a two-layer gabor graph with those knobs
    cat <<G
{"frames": "1", "knobs": $1, "nodes": {
 "plate": {"node": "synth", "scene": "orbit", "size": "96x72"},
 "strokes1": {"node": "gabor-splat", "inputs": {"anchor": "plate:Pref", "depth": "plate:Z"}, "params": {"radius": 6, "seed": 1}},
 "strokes2": {"node": "gabor-splat", "inputs": {"anchor": "plate:Pref", "depth": "plate:Z"}, "params": {"radius": 9, "seed": 2}},
 "strokes": {"node": "blend", "inputs": {"base": "strokes1", "layer": "strokes2"}, "params": {"mode": "screen"}},
 "w": {"node": "write", "inputs": {"image": "strokes"}, "path": "out.exr"}}}
G
}
graph '["strokes1.nope"]' >bad1.json
expect_rc 2 "$NPRFX" help bad1.json
has last.err "knobs: 'strokes1.nope': node 'strokes1' (gabor-splat) has no param 'nope'"
graph '["brushes*.radius"]' >bad2.json
expect_rc 2 "$NPRFX" help bad2.json
has last.err "knobs: 'brushes*.radius' names no processing node of the graph with that param"
graph '[3]' >bad3.json
expect_rc 2 "$NPRFX" help bad3.json
has last.err "knobs: entry 1 is not \"NODE.PARAM\""
graph '[{"param": "strokes1.radius", "label": "x"}]' >bad4.json
expect_rc 2 "$NPRFX" help bad4.json
has last.err "knobs: entry 1: unexpected 'label' (expected param, help)"
graph '"strokes1.radius"' >bad5.json
expect_rc 2 "$NPRFX" help bad5.json
has last.err "top-level entry 'knobs' must be a list"

# --set with a *: the nodes that match and have the param (not the blend named strokes), the
# same pixels as setting each; a pattern matching nothing is refused.
graph '["strokes*.radius"]' >ok.json
expect_rc 0 "$NPRFX" help ok.json
has last.out "strokes*.radius"
has last.out "double, 6;"
has last.out "(2 nodes)"
expect_rc 0 "$NPRFX" run ok.json --quiet --set 'strokes*.radius=14' --set w.path=star.exr
expect_rc 0 "$NPRFX" run ok.json --quiet --set strokes1.radius=14 --set strokes2.radius=14 --set w.path=each.exr
expect_rc 0 "$NPRFX" run ok.json --quiet --set w.path=plain.exr
expect_rc 0 "$NPRFX" diff star.exr each.exr --fail 0 --warn 0 -q
expect_rc 2 "$NPRFX" diff star.exr plain.exr --fail 0 --warn 0 -q
expect_rc 2 "$NPRFX" run ok.json --quiet --set 'brush*.radius=3'
has last.err "no processing node of the graph matches 'brush*' and has a param 'radius'"
echo "knobs: passed"
