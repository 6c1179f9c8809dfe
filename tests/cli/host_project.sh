#!/usr/bin/env bash
# nprfx host-project: the sample host files in samples/hosts are what the command writes from
# samples/graphs/main.json (no drift), the Natron project holds the graph's nodes, non-default
# params, connections, format and frames, the Natron script sets the same params and does not
# need __file__, and graphs hosts cannot express fail with the node's name. With --look the
# graph is one look node per output on a Read (samples/hosts/*_look.*, no drift either); with
# --look-clips each AOV the look reads is a Shuffle into its own clip. A script of several
# writers lists the commands that render each alone.
set -u
NPRFX=$1; SRC=$2; W=$3
rm -rf "$W"; mkdir -p "$W/samples/graphs" "$W/samples/hosts"; cd "$W"
fails=0
fail() { echo "FAIL: $*"; fails=$((fails+1)); }
REGEN="nprfx host-project samples/graphs/main.json --natron samples/hosts/nprfx_crossing.ntp --natron-script samples/hosts/nprfx_crossing_natron.py --nuke samples/hosts/nprfx_crossing.nk"
REGEN_LOOK="nprfx host-project samples/graphs/main.json --look --natron samples/hosts/nprfx_crossing_look.ntp --natron-script samples/hosts/nprfx_crossing_look_natron.py --nuke samples/hosts/nprfx_crossing_look.nk"

# (1) the same layout as the sources, so relative paths come out the same
cp "$SRC/samples/graphs/main.json" samples/graphs/
# the command reads the first plate's header only
mkdir -p samples/plates/crossing
cp "$SRC/samples/plates/crossing/crossing.0001.exr" samples/plates/crossing/
"$NPRFX" host-project samples/graphs/main.json --natron samples/hosts/nprfx_crossing.ntp \
    --natron-script samples/hosts/nprfx_crossing_natron.py --nuke samples/hosts/nprfx_crossing.nk ||
    fail "host-project exited $?"
for f in nprfx_crossing.ntp nprfx_crossing_natron.py nprfx_crossing.nk; do
    cmp -s "samples/hosts/$f" "$SRC/samples/hosts/$f" ||
        fail "samples/hosts/$f differs from what the graph gives; regenerate from the source folder: $REGEN"
done
"$NPRFX" host-project samples/graphs/main.json --look --natron samples/hosts/nprfx_crossing_look.ntp \
    --natron-script samples/hosts/nprfx_crossing_look_natron.py \
    --nuke samples/hosts/nprfx_crossing_look.nk || fail "host-project --look exited $?"
for f in nprfx_crossing_look.ntp nprfx_crossing_look_natron.py nprfx_crossing_look.nk; do
    cmp -s "samples/hosts/$f" "$SRC/samples/hosts/$f" ||
        fail "samples/hosts/$f differs from what the graph gives; regenerate from the source folder: $REGEN_LOOK"
done
# several writers: the script says to render them one at a time (NatronRenderer 2.5 can stall
# with several at once); a graph with one writer gets no such lines
for w in w_pencil w_noise; do
    grep -q "^#   NatronRenderer -w $w 1-24 " samples/hosts/nprfx_crossing_natron.py ||
        fail "the Natron script of two writers does not say how to render $w alone"
done
cp "$SRC/samples/graphs/toon.json" samples/graphs/
"$NPRFX" host-project samples/graphs/toon.json --natron-script toon_natron.py >/dev/null 2>&1 ||
    fail "host-project toon.json exited $?"
if [ ! -s toon_natron.py ] || grep -q "NatronRenderer -w" toon_natron.py; then
    fail "the Natron script of one writer lists per-writer renders (or was not written)"
fi
NTP=${NTP:-samples/hosts/nprfx_crossing.ntp}
PY=${PY:-samples/hosts/nprfx_crossing_natron.py}

# (2) the project: "node knob value" of every org.nprfx node, inputs, format, frames
awk '
/<Name>frameRange</ { fr = 1 }
/<RectI/ { rect = 1 }
/<Plugin_script_name>/ { gsub(/.*<Plugin_script_name>|<\/Plugin_script_name>.*/, ""); node = $0 }
/<Plugin_id>/ { nprfx = index($0, "org.nprfx.") > 0 }
/<Name>/ { gsub(/.*<Name>|<\/Name>.*/, ""); knob = $0; nval = 0 }
/<Value>/ && nprfx { gsub(/.*<Value>|<\/Value>.*/, ""); if (!nval++) print "param", node, knob, $0 + 0 }
/<ChoiceLabel>/ && nprfx { gsub(/.*<ChoiceLabel>|<\/ChoiceLabel>.*/, ""); print "choice", node, knob, $0 }
/<first>/ { gsub(/.*<first>|<\/first>.*/, ""); first = $0 }
/<second>/ && nprfx { gsub(/.*<second>|<\/second>.*/, ""); print "input", node, first, $0 }
fr && /<Value>/ { gsub(/.*<Value>|<\/Value>.*/, ""); range = range " " $0; if (++frn == 2) { print "frames" range; fr = 0 } }
rect && /<Right>/ { gsub(/.*<Right>|<\/Right>.*/, ""); right = $0 }
rect && /<Top>/ { gsub(/.*<Top>|<\/Top>.*/, ""); print "format", right "x" $0; rect = 0 }
' "$NTP" | grep -v "Channels" | sort > ntp.txt
sort > want.txt <<'WANT'
choice noise noise bandpass
choice noise output unit01
choice strokes mode builtin
format 320x180
frames 1 24
input light Albedo plate_DiffCol_RGB
input light Coverage matte
input light Tone plate_Combined_RGB
input look Alpha strokes
input look Base paper
input look Layer plate_Combined_RGB
input matte Depth plate_Depth_Z
input matte Object ID plate_IndexOB_X
input noise Depth plate_Depth_Z
input noise Motion Prev plate_motion_prev_XY
input paper Image plate_Combined_RGB
input strokes Pattern noise
input strokes Tone light
param light out_high 0.6
param light out_low 0.2
param look gain_layer 0.85
param matte designWidth 1280
param noise contrast 0.2
param noise designWidth 1280
param noise sigma_hi 2.5
param paper designWidth 1280
param strokes invert 1
param strokes sigma 10
WANT
# choices also give a "param" line (their index): keep the labels only
grep -v -e '^param noise noise' -e '^param noise output' -e '^param strokes mode' ntp.txt > got.txt
diff want.txt got.txt > ntp.diff || { fail "$NTP: nodes, params or inputs are not the graph's:"; cat ntp.diff; }
# the defaults main.json leaves are not written
for p in "noise sigma_lo" "noise alpha"; do
    grep -q "^param $p " ntp.txt && fail "$NTP sets $p, which main.json leaves at its default"
done

# (3) the script: the same params by script name (node variables are n_NAME), and no __file__
# outside the try
grep -o '^    n_[a-z_]*\.getParam("[a-zA-Z_]*")\.setValue([^)]*)' "$PY" |
    sed 's/^ *n_\([a-z_]*\)\.getParam("\([a-zA-Z_]*\)")\.setValue(\(.*\))/param \1 \2 \3/; s/True$/1/' |
    awk '{ print $1, $2, $3, $4 + 0 }' | sort > py.txt
grep '^param' want.txt > want_py.txt
diff want_py.txt py.txt > py.diff || { fail "$PY: params differ from the graph's:"; cat py.diff; }
grep -n '__file__' "$PY" | grep -v -e 'abspath(__file__)' -e 'without __file__' > file.txt &&
    { fail "$PY uses __file__ outside the NameError guard:"; cat file.txt; }
grep -q 'except NameError' "$PY" || fail "$PY has no NameError guard around __file__"

# (4) the scripts run as Natron 2.5 runs them (tests/cli/lib/natron_stub.py: no __file__, the
# current folder the user's): the sample from the folder above samples/ writes beside the
# script's folder; a graph with a node named "base" (painterly's) builds; with an absolute plate
# path the script finds its folder by its own file, and from an unrelated folder it says so
# instead of writing below a folder that does not exist; no choice is left unset.
stub() { # DIR SCRIPT: run SCRIPT from DIR, output in stub.out
    (cd "$1" && python3 "$SRC/tests/cli/lib/natron_stub.py" "$2") > stub.out 2>&1 ||
        { fail "$2 failed under the Natron stand-in:"; cat stub.out; }
}
stub . "$PY"
grep -q "^writer $PWD/samples/hosts/out/main/pencil.####.exr$" stub.out ||
    { fail "$PY writes elsewhere than beside its folder:"; cat stub.out; }
grep -q 'has no option' stub.out && { fail "$PY leaves a choice unset:"; cat stub.out; }
mkdir -p abs/hosts elsewhere
cp "$SRC/samples/graphs/painterly.json" samples/graphs/
"$NPRFX" host-project samples/graphs/painterly.json --natron-script abs/hosts/painterly.py \
    --set "plate.path=$PWD/samples/plates/crossing/crossing.####.exr" 2>err.txt ||
    { fail "host-project of painterly.json failed:"; cat err.txt; }
stub . abs/hosts/painterly.py
grep -q "^writer $PWD/abs/hosts/out/painterly/painterly.####.exr$" stub.out ||
    { fail "abs/hosts/painterly.py (absolute plate) writes elsewhere than beside its folder:"; cat stub.out; }
grep -q "^reader $PWD/samples/plates/crossing/crossing.####.exr$" stub.out ||
    { fail "abs/hosts/painterly.py reads another plate:"; cat stub.out; }
stub elsewhere "$PWD/abs/hosts/painterly.py"
grep -q "painterly.py not found in" stub.out ||
    { fail "run from an unrelated folder, the script does not say it cannot find its folder:"; cat stub.out; }
# A plate of plain R, G, B (footage): the Shuffles take the A input's own RGBA ("A.r", the
# options' first four), in the project and the script, never a label Natron cannot resolve.
mkdir -p samples/footage/dolly plain/hosts
cp "$SRC/samples/footage/dolly/dolly.0001.png" samples/footage/dolly/
cp "$SRC/samples/graphs/footage_pencil.json" samples/graphs/
"$NPRFX" host-project samples/graphs/footage_pencil.json --natron plain/hosts/plain.ntp \
    --natron-script plain/hosts/plain.py 2>err.txt || { fail "host-project of footage_pencil.json failed:"; cat err.txt; }
stub . plain/hosts/plain.py
for c in "outputR A.r" "outputG A.g" "outputB A.b"; do
    grep -q "^choice plate_RGB $c$" stub.out || { fail "plain/hosts/plain.py: plate_RGB $c not chosen:"; cat stub.out; }
done
# the project's Shuffle: each output's value (the option's index) and its label
awk '/<Name>output[RGB]</ { k = $0; gsub(/.*<Name>|<\/Name>.*/, "", k) }
     k && /<Value>/ { v = $0; gsub(/.*<Value>|<\/Value>.*/, "", v) }
     k && /<ChoiceLabel>/ { l = $0; gsub(/.*<ChoiceLabel>|<\/ChoiceLabel>.*/, "", l); print k, v, l; k = "" }' \
    plain/hosts/plain.ntp | head -3 > plain.txt
printf 'outputR 0 A.r\noutputG 1 A.g\noutputB 2 A.b\n' | diff - plain.txt > plain.diff ||
    { fail "plain/hosts/plain.ntp: the Shuffle's options are not the A input's RGB:"; cat plain.diff; }

# (5) looks: main.json's two outputs are two look nodes on the Read (the second showing w_noise),
# each feeding its write; in the script too, under the Natron stand-in. toon.json with its clips:
# a Shuffle per AOV into the clips, a turned knob set by its param name.
LNTP=samples/hosts/nprfx_crossing_look.ntp
awk '/<Plugin_script_name>/ { gsub(/.*<Plugin_script_name>|<\/Plugin_script_name>.*/, ""); node = $0 }
     /<Plugin_id>/ { look = index($0, "org.nprfx.look.Main") > 0 }
     /<first>/ { gsub(/.*<first>|<\/first>.*/, ""); first = $0 }
     /<second>/ { gsub(/.*<second>|<\/second>.*/, ""); print "input", node, first, $0 }
     look && /<Name>output</ { o = 1 }
     o && /<ChoiceLabel>/ { gsub(/.*<ChoiceLabel>|<\/ChoiceLabel>.*/, ""); print "choice", node, "output", $0; o = 0 }' \
    "$LNTP" | sort > look.txt
printf '%s\n' "choice Main_w_noise output w_noise" "input Main_w_noise Source plate" \
    "input Main_w_pencil Source plate" "input Viewer1 1 Main_w_pencil" "input w_noise Source Main_w_noise" \
    "input w_pencil Source Main_w_pencil" | sort > want_look.txt
diff want_look.txt look.txt > look.diff || { fail "$LNTP: not one look node per output on the Read:"; cat look.diff; }
[ "$(grep -c 'org.nprfx.look.Main' "$LNTP")" -eq 2 ] || fail "$LNTP: not two look nodes"
grep -c "Shuffle" "$LNTP" | grep -qx 0 || fail "$LNTP (layers): Shuffles where Source takes the Read whole"
stub . samples/hosts/nprfx_crossing_look_natron.py
grep -q "^node org.nprfx.look.Main$" stub.out || { fail "the look script makes no look node:"; cat stub.out; }
cp "$SRC/samples/graphs/toon.json" samples/graphs/
"$NPRFX" host-project samples/graphs/toon.json --look-clips --nuke toon_clips.nk --set ink.width=3 2>err.txt ||
    { fail "host-project --look-clips of toon.json failed:"; cat err.txt; }
grep -q "^ ink_width 3$" toon_clips.nk || fail "toon_clips.nk: the turned knob ink.width is not set"
grep -q "inputs: 0 Source 1 Albedo 2 Depth 3 Normal 4 ID 5 MotionPrev" toon_clips.nk ||
    { fail "toon_clips.nk: the look's clips are not connected:"; grep -A4 OFXorg toon_clips.nk; }
grep -q "label \"ViewLayer.Depth.Z\"" toon_clips.nk || fail "toon_clips.nk: no Shuffle of the depth AOV"
grep -q "^ bands_bands " toon_clips.nk && fail "toon_clips.nk sets a knob --set left alone"
printf '{"frames": "1", "nodes": {"s": {"node": "synth", "scene": "orbit", "size": "32x24"}, "w": {"node": "write", "inputs": {"image": "s"}, "path": "o/x.####.exr"}}}\n' > synth_look.json
"$NPRFX" host-project synth_look.json --look --nuke bad.nk 2>err.txt && fail "a graph that is no look was accepted by --look"
grep -q "synth_look.json is no look: it reads no frame sequence" err.txt ||
    { fail "--look on a graph that is no look says not why:"; cat err.txt; }

# (6) graphs hosts cannot express
printf '{"frames": "1-2", "nodes": {"s": {"node": "synth", "scene": "orbit", "size": "32x24"}, "b": {"node": "blend", "inputs": {"base": "s", "layer": "s"}}, "w": {"node": "write", "inputs": {"image": "b"}, "path": "o/x.####.exr"}}}\n' > synth.json
"$NPRFX" host-project synth.json --natron bad.ntp 2> err.txt && fail "a synth graph was accepted"
grep -q "synth.json.*node 's'" err.txt || { fail "the synth error names no file and node:"; cat err.txt; }
[ -e bad.ntp ] && fail "a failed host-project left bad.ntp"
"$NPRFX" host-project samples/graphs/main.json 2> err.txt && fail "no output was accepted"
grep -q -- "--natron" err.txt || fail "no hint about the outputs: $(cat err.txt)"
"$NPRFX" host-project --help | grep -q "Natron" || fail "--help does not teach"

[ $fails -eq 0 ] && echo "host_project: ok"
exit $((fails > 0))
