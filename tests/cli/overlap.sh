# A run overlaps its frames: the next frame's plates decode while a frame computes, a plate the
# frame waits for is decoded by every worker a band each, and with 4 or more threads a frame's
# files are written while the next computes. None of it changes a pixel: every frame equals a
# serial one-thread run's, in order, out of order, alone, with the shot's analysis, and under a
# memory limit the writes in the background must wait for. A write that fails in the background
# fails its own frame, named, and the others are written.
# usage: bash overlap.sh NPRFX SOURCE_DIR WORK_DIR
set -eu
. "$(dirname "$0")/lib/check.sh"
NPRFX=$1
SRC=$2
WORK=$3
work_in "$WORK"

"$NPRFX" synth orbit --frames 1-6 --size 320x180 --threads 2 -o plates/o.####.exr >/dev/null
PLATE="plate.path=$WORK/plates/o.####.exr"

# same GRAPH_STEM WRITES DIR: every write's frames 1-6 in DIR equal ref's, bit for bit
same() {
    for w in $2; do
        expect_rc 0 "$NPRFX" diff "ref/out/$1/$w.####.exr" "$3/out/$1/$w.####.exr" --frames 1-6 \
            --fail 0 --warn 0
        grep -qx PASS last.out || fail "$3: $1's $w differs from the serial run"
    done
}

# main: a shot-wide tone range; coherent_noise_fig2: a temporal node (the frame before).
for g in main:main:pencil,noise coherent_noise_fig2:fig2:noise,difference; do
    graph=$SRC/samples/graphs/${g%%:*}.json
    rest=${g#*:}
    stem=${rest%%:*}
    writes=$(echo "${rest#*:}" | tr ',' ' ')
    run() { expect_rc 0 "$NPRFX" run "$graph" --set "$PLATE" --shot 1-6 --analysis off "$@"; }
    run --serial --threads 1 --output-dir ref -q
    run --threads 2 --output-dir t2 -q
    same "$stem" "$writes" t2
    # 4 threads: writes in the background; progress names every frame once, in order
    run --threads 4 --output-dir t4
    [ "$(grep -c '^frame ' last.err)" -eq 6 ] || fail "t4: not one progress line a frame"
    [ "$(grep '^frame ' last.err | awk '{print $2}' | tr '\n' ' ')" = "1 2 3 4 5 6 " ] ||
        fail "t4: frames reported out of order"
    same "$stem" "$writes" t4
    run --threads 4 --frames 6-1 --output-dir rev -q
    same "$stem" "$writes" rev
    run --threads 4 --frames 2,5,1,6,3,4 --output-dir odd -q
    same "$stem" "$writes" odd
    for f in 1 2 3 4 5 6; do
        run --threads 4 --frames "$f" --output-dir alone -q
    done
    same "$stem" "$writes" alone
    expect_rc 0 "$NPRFX" analyze "$graph" --set "$PLATE" --shot 1-6 --threads 2 --output-dir an -q
    expect_rc 0 "$NPRFX" run "$graph" --set "$PLATE" --shot 1-6 --threads 4 --output-dir an -q
    same "$stem" "$writes" an
done

# Under a memory limit that leaves no room for a frame beside the writes still running: the
# frame waits for them, and the limit holds.
graph=$SRC/samples/graphs/main.json
expect_rc 0 "$NPRFX" analyze "$graph" --set "$PLATE" --shot 1-6 --threads 2 --output-dir lim -q
expect_rc 0 "$NPRFX" run "$graph" --set "$PLATE" --shot 1-6 --threads 4 --output-dir lim \
    --mem-limit 12M --stats -q
held=$(sed -n 's/^frames and caches held at most \([0-9.]*\) MiB.*/\1/p' last.out)
[ -n "$held" ] || { cat last.out; fail "no 'held at most' in --stats"; }
awk -v h="$held" 'BEGIN { exit !(h <= 12.0) }' || fail "held $held MiB under a 12 MiB limit"
same main "pencil noise" lim

# A write that fails in the background (its file's name taken by a directory) fails frame 3,
# named, and only frame 3: --keep-going writes the others.
rm -rf bad
mkdir -p bad/out/main/pencil.0003.exr
expect_rc 1 "$NPRFX" run "$graph" --set "$PLATE" --shot 1-6 --analysis off --threads 4 \
    --output-dir bad --keep-going
has last.err "frame 3 failed"
has last.err "pencil.0003.exr"
[ "$(grep -c 'failed:' last.err)" -eq 1 ] || fail "more than frame 3 failed"
has last.err "1 of 6 frames failed"
for f in 1 2 4 5 6; do
    [ -f "bad/out/main/pencil.000$f.exr" ] || fail "frame $f was not written after frame 3 failed"
done
[ -d bad/out/main/pencil.0003.exr ] || fail "the directory in frame 3's way was touched"
# without --keep-going the run stops at the failed frame, after reporting the frame it was
# computing meanwhile
rm -rf bad/out/main/pencil.000[1245]* bad/out/main/pencil.0006*
expect_rc 1 "$NPRFX" run "$graph" --set "$PLATE" --shot 1-6 --analysis off --threads 4 \
    --output-dir bad
has last.err "frame 3 failed"
[ ! -f bad/out/main/pencil.0006.exr ] || fail "the run went on after frame 3 failed"
echo "overlap: ok"
