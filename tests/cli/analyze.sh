# nprfx analyze: the shot statistics (a tone range over the shot) measured once and stored beside
# the outputs. A run that finds them renders its frames without reading the rest of the shot, and
# its pixels equal a run that measures (in any frame order); plates changed since, another shot,
# a frame whose fingerprint differs and a broken file all measure again, with a note. nprfx farm
# submits the analysis as a first job the chunks depend on; its chunks, run by hand, match one
# sequential run.
# usage: bash analyze.sh NPRFX SOURCE_DIR WORK_DIR
set -eu
. "$(dirname "$0")/lib/check.sh"
NPRFX=$1
WORK=$3
rm -rf "$WORK"
mkdir -p "$WORK"
cd "$WORK"

# How many times the --stats table says node $2 rendered (plate reads for a read node).
renders() { awk -v n="$2" '$1 == n { print $3 }' "$1"; }
same() { # same A_DIR B_DIR FRAMES: every frame of the tone's output equal, bit for bit
    expect_rc 0 "$NPRFX" diff "$1/tone.####.exr" "$2/tone.####.exr" --frames "$3" --fail 0 --warn 0
    grep -qx PASS last.out || fail "$1 and $2 differ at frames $3"
}

"$NPRFX" synth orbit --frames 1-24 --size 160x90 --threads 2 -o plates/orbit.####.exr >/dev/null
cat >g.json <<'EOF'
{
  "frames": "1-24",
  "nodes": {
    "plate": {"node": "read", "path": "plates/orbit.####.exr"},
    "light": {"node": "tone", "inputs": {"tone": "plate:R,G,B", "albedo": "plate:albedo"},
              "params": {"range": "shot", "low": 2, "high": 98}},
    "out": {"node": "write", "inputs": {"image": "light"}, "path": "out/tone.####.exr"}
  }
}
EOF

# --- Measured once, beside the outputs.
expect_rc 0 "$NPRFX" analyze g.json --threads 2
has last.out "measured 1 node over frames 1-24"
A=out/g.analysis.json
[ -f "$A" ] || fail "no $A"
has $A '"shot": [1, 24]'
has $A '"range shot"'
[ "$(grep -o '"fingerprints [0-9a-f ]*"' $A | wc -w)" -eq 25 ] || fail "not 24 fingerprints in $A"
[ -z "$(ls out | grep tmp)" ] || fail "a temporary file left: $(ls out)"

# --- A run from it reads only its frames; one that measures reads the whole shot; same pixels.
# (--output-dir moves the default analysis with the outputs: name it)
expect_rc 0 "$NPRFX" run g.json --frames 10-12 --stats --threads 2 --output-dir seeded --analysis $A
has last.err "note: the shot statistics of 1 node from $A"
[ "$(renders last.out plate)" = 3 ] || fail "a seeded run read the plate $(renders last.out plate) times for 3 frames"
expect_rc 0 "$NPRFX" run g.json --frames 10-12 --stats --threads 2 --output-dir measured --analysis off
lacks last.err "shot statistics"
[ "$(renders last.out plate)" = 24 ] || fail "a measuring run read the plate $(renders last.out plate) times"
same seeded/out measured/out 10-12
# The default: found beside the outputs, in any frame order.
expect_rc 0 "$NPRFX" run g.json --frames 12,3,20,7 --stats --threads 2
has last.err "note: the shot statistics of 1 node from $A"
[ "$(renders last.out plate)" = 4 ] || fail "read the plate $(renders last.out plate) times for 4 frames"
expect_rc 0 "$NPRFX" run g.json --frames 3,7,12,20 --threads 2 --output-dir measured --analysis off
same out measured/out 3,7,12,20

# --- A frame whose fingerprint differs from the analysis: measured again, with a note, same pixels.
sed 's/"fingerprints \([0-9a-f]*\) \([0-9a-f]*\) /"fingerprints \1 0000000000000000 /' $A >tampered.json
cmp -s $A tampered.json && fail "the fingerprint was not changed"
expect_rc 0 "$NPRFX" run g.json --frames 1-3 --stats --threads 2 --output-dir t --analysis tampered.json
has last.err "node 'light': frame 2 differs from what tampered.json measured: the shot was measured again"
[ "$(renders last.out plate)" = 24 ] || fail "read the plate $(renders last.out plate) times re-measuring"
expect_rc 0 "$NPRFX" run g.json --frames 1-3 --threads 2 --output-dir measured --analysis off
same t/out measured/out 1-3

# --- Another shot: not used.
expect_rc 0 "$NPRFX" run g.json --shot 1-20 --frames 5 --stats --threads 2 --output-dir s20 --analysis $A
has last.err "measured the shot 1-24, this run's shot is 1-20: measuring it again"
[ "$(renders last.out plate)" = 20 ] || fail "read the plate $(renders last.out plate) times for a 20-frame shot"

# --- Plates changed since the analysis: not used, and the pixels follow the new plates.
cp plates/orbit.0003.exr plates/orbit.0020.exr
expect_rc 0 "$NPRFX" run g.json --frames 10 --stats --threads 2 --output-dir changed --analysis $A
has last.err "changed since they were measured (a file's size or time differs): measuring the shot again"
[ "$(renders last.out plate)" = 24 ] || fail "a stale analysis was used"
expect_rc 0 "$NPRFX" run g.json --frames 10 --threads 2 --output-dir changed_off --analysis off
same changed/out changed_off/out 10
# The comparison can fail: the new frame 20 changes the shot's range, so the old one is wrong.
rc=0
"$NPRFX" diff changed/out/tone.0010.exr measured/out/tone.0010.exr --fail 0 --warn 0 -q >/dev/null 2>&1 || rc=$?
[ "$rc" -eq 2 ] || fail "changing frame 20 did not change the shot's range (diff exited $rc): the check proves nothing"
# Analysed again on the new plates: used again.
expect_rc 0 "$NPRFX" analyze g.json --threads 2 -q
expect_rc 0 "$NPRFX" run g.json --frames 10 --stats --threads 2 --output-dir changed2 --analysis $A
has last.err "note: the shot statistics of 1 node from"
[ "$(renders last.out plate)" = 1 ] || fail "the new analysis was not used"
same changed2/out changed_off/out 10

# --- A broken or missing file costs a measurement, never the run.
echo '{"nprfx_analysis": 1, "shot": [1,' >broken.json
expect_rc 0 "$NPRFX" run g.json --frames 10 --threads 2 --output-dir broken --analysis broken.json
has last.err "warning: g.json: broken.json: malformed JSON"
has last.err "measuring the shot in this run"
same broken/out changed_off/out 10
expect_rc 0 "$NPRFX" run g.json --frames 10 --threads 2 --output-dir missing --analysis nowhere.json
has last.err "cannot open analysis 'nowhere.json'"

# --- What analyze refuses, and its help.
expect_rc 2 "$NPRFX" analyze g.json --frames 3
has last.err "nprfx analyze: --frames: it measures the whole shot"
expect_rc 0 "$NPRFX" analyze --help
has last.out "usage: nprfx analyze GRAPH.json"
expect_rc 0 "$NPRFX" run --help
has last.out "--analysis PATH"

# --- The farm: an analysis job first, the chunks after it succeeded, each reading the file.
rm -rf out
expect_rc 0 "$NPRFX" farm g.json --frames 1-24 --chunk 6 --emit jobs --cpus 2
has last.out "analyze.sbatch (the shot statistics, into $PWD/out/g.analysis.json)"
for f in jobs/analyze.sbatch jobs/render.sbatch jobs/submit.sh; do bash -n $f || fail "$f is not valid shell"; done
has jobs/analyze.sbatch "analyze $PWD/g.json --analysis $PWD/out/g.analysis.json --threads"
has jobs/render.sbatch "run $PWD/g.json --analysis $PWD/out/g.analysis.json --frames"
has jobs/submit.sh '--dependency=afterok:"$analyze"'
SLURM_CPUS_PER_TASK=2 bash jobs/analyze.sbatch >analyze.log 2>&1 || { cat analyze.log >&2; fail "the analysis job failed"; }
for t in 3 2 1 0; do
    SLURM_ARRAY_TASK_ID=$t SLURM_CPUS_PER_TASK=2 bash jobs/render.sbatch >chunk$t.log 2>&1 ||
        { cat chunk$t.log >&2; fail "chunk $t failed"; }
    has chunk$t.log "note: the shot statistics of 1 node from $PWD/out/g.analysis.json"
done
expect_rc 0 "$NPRFX" run g.json --frames 1-24 --threads 2 --output-dir seq --analysis off -q
same seq/out out 1-24
# A graph without a node that measures its shot has no analysis job.
cat >copy.json <<'EOF'
{"frames": "1-24", "nodes": {"plate": {"node": "read", "path": "plates/orbit.####.exr"},
 "out": {"node": "write", "inputs": {"image": "plate:R,G,B"}, "path": "copy/c.####.exr"}}}
EOF
expect_rc 0 "$NPRFX" farm copy.json --frames 1-24 --chunk 6 --emit jobs2
[ ! -e jobs2/analyze.sbatch ] || fail "an analysis job for a graph that measures nothing"
lacks jobs2/submit.sh "afterok"
# --- OpenFX: the Analyze Shot button of a tone plug-in measures in the instance-changed action;
# the first render then declares and fetches its own frame alone (the test host checks that the
# frames fetched are the frames declared), and the pixels are the runner's.
OFXTEST=${NPRFX_OFXTEST:-$(dirname "$NPRFX")/nprfx-ofxtest}
BUNDLE=$(cd "$(dirname "$NPRFX")" && pwd)/plugins/ofx/nprfx.ofx.bundle
if [ -x "$OFXTEST" ] && [ -d "$BUNDLE" ]; then
    expect_rc 0 "$OFXTEST" run g.json --ofx "$BUNDLE" --frames 5-7 --output-dir ofx_a \
        --analysis off --analyze-shot -q
    expect_rc 0 "$NPRFX" run g.json --frames 5-7 --output-dir run_a --analysis off -q
    same ofx_a/out run_a/out 5-7
    expect_rc 0 "$OFXTEST" run g.json --ofx "$BUNDLE" --frames 5-7 --output-dir ofx_b \
        --analysis off -q
    same ofx_b/out run_a/out 5-7
else
    echo "analyze: no OpenFX test host next to $NPRFX: the Analyze Shot button is not checked"
fi
echo "analyze: ok"
