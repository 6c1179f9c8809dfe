#!/bin/bash
# Every shipped style end to end, as a TD runs it: `nprfx run STYLE.json` on a plate of WxH
# (synthetic, Blender layout, half floats, only the passes the style reads), plate read to files
# written, per style: the first frame and the steady frames apart, the plate read and the writes
# alone (from --stats), the graph's compute alone (nprfx bench-graph, same size and threads), and
# peak resident memory. The I/O floor beside them: oiiotool reading the same plate and writing
# its RGB. Prints a Markdown table (docs/performance.md).
#
# usage: samples/bench/end_to_end.sh [NPRFX] [WxH] [THREADS] [FRAMES] [STYLES...]
#        (defaults: build/nprfx 1920x1080 2 6, every style of samples/graphs the README shows)
set -eu
NPRFX=${1:-build/nprfx}
SIZE=${2:-1920x1080}
T=${3:-2}
N=${4:-6}
shift $(($# < 4 ? $# : 4))
STYLES=${*:-main stippling cross_hatching graphite chalk color_strokes watercolor ink_on_canvas painterly painterly_pam toon}
HERE=$(cd "$(dirname "$0")/../.." && pwd)
command -v oiiotool > /dev/null || { echo "end_to_end.sh: needs oiiotool (Debian: openimageio-tools)" >&2; exit 2; }
[ -x "$NPRFX" ] || { echo "end_to_end.sh: no nprfx at $NPRFX (build first, or pass its path)" >&2; exit 2; }
NPRFX=$(cd "$(dirname "$NPRFX")" && pwd)/$(basename "$NPRFX")
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
cd "$dir"
"$NPRFX" synth orbit --layout blender --half --size "$SIZE" --frames 1-$N --threads "$T" \
    -o whole/o.####.exr > /dev/null

echo "| style | first frame s | steady frame s | plate read ms | writes ms | compute alone ms | peak RSS MiB | channels read |"
echo "|---|---|---|---|---|---|---|---|"
for s in $STYLES; do
    g=$HERE/samples/graphs/$s.json
    set_plate="plate.path=$dir/whole/o.####.exr"
    # the passes it reads: a plate of those alone
    "$NPRFX" run "$g" --set "$set_plate" --shot 1-$N --frames 1 --threads "$T" --stats --quiet \
        --output-dir probe --analysis off > probe.txt 2>&1 || { echo "| $s | failed: $(tail -1 probe.txt) |"; continue; }
    chans=$(sed -n "s/^read 'plate' takes [0-9]* of its files' [0-9]* channels: //p" probe.txt)
    rm -rf "p_$s"
    mkdir -p "p_$s"
    for f in $(seq 1 $N); do
        oiiotool "whole/o.$(printf %04d $f).exr" --ch "$chans" -d half --compression zip \
            -o "p_$s/o.$(printf %04d $f).exr" 2> /dev/null
    done
    set_plate="plate.path=$dir/p_$s/o.####.exr"
    "$NPRFX" analyze "$g" --set "$set_plate" --shot 1-$N --threads "$T" --output-dir "o_$s" -q
    /usr/bin/time -f "%M" -o rss.txt "$NPRFX" run "$g" --set "$set_plate" --shot 1-$N \
        --threads "$T" --stats --output-dir "o_$s" > run.txt 2> prog.txt
    first=$(awk '/^frame /{print $4; exit}' prog.txt)
    steady=$(awk '/^frame /{n++; if (n > 1) {s += $4; k++}} END {printf "%.2f", k ? s / k : 0}' prog.txt)
    read_ms=$(awk '$1 == "plate" && $2 == "read" {print $4}' run.txt)
    writes=$(awk '$2 == "write" {s += $4} END {printf "%.0f", s}' run.txt)
    compute=$("$NPRFX" bench-graph "$g" --size "$SIZE" --frames $N --threads "$T" 2> /dev/null |
        sed -n 's/.*compute \([0-9.]*\) ms.*/\1/p' | head -1)
    rss=$(( $(cat rss.txt) / 1024 ))
    echo "| $s | $first | $steady | $read_ms | $writes | ${compute:-?} | $rss | $(echo "$chans" | tr ',' '\n' | wc -l) |"
done
# The I/O floor: oiiotool reading the whole half plate and writing its RGB (one frame).
t0=$(date +%s.%N)
oiiotool --threads "$T" whole/o.0001.exr --ch R,G,B -o floor.exr 2> /dev/null ||
    oiiotool --threads "$T" whole/o.0001.exr --ch ViewLayer.Combined.R,ViewLayer.Combined.G,ViewLayer.Combined.B -o floor.exr
t1=$(date +%s.%N)
echo
nch=$("$NPRFX" info whole/o.0001.exr | sed -n '1s/.* \([0-9]*\) channels.*/\1/p')
echo "I/O floor: oiiotool reads one $SIZE frame of the whole plate ($nch half channels, zip) and writes its RGB in $(echo "$t1 - $t0" | bc) s"
