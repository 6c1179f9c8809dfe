# nprfx farm without a cluster: the Slurm job files for 48 frames in chunks of 5, their
# chunks run by hand with SLURM_ARRAY_TASK_ID set (two at a time, last first) and compared exactly
# with one sequential run, --submit through a stand-in sbatch, `farm check` on a deleted, a
# truncated and a complete sequence, and the requests refused before anything is written.
# tests/cli/farm_slurm.sh does the same on a real single-node Slurm cluster.
# usage: bash farm.sh NPRFX SOURCE_DIR WORK_DIR
set -eu
NPRFX=$1
WORK=$3
rm -rf "$WORK"
mkdir -p "$WORK"
cd "$WORK"

fail() {
    echo "FAIL: $*" >&2
    exit 1
}
expect_rc() {
    local want=$1 rc=0
    shift
    "$@" >last.out 2>last.err || rc=$?
    [ "$rc" -eq "$want" ] || { cat last.out last.err >&2; fail "'$*' exited $rc, expected $want"; }
}
has() { grep -qF -- "$2" "$1" || { cat "$1" >&2; fail "$1 lacks: $2"; }; }
# The lock test's flock(1) holder waits for this file: made on any exit, so it never outlives us.
trap 'touch "$WORK/release" 2>/dev/null || true' EXIT

# 48 frames of plates; a coherent-noise graph with no "frames" of its own, so the chunks must be
# given the whole range as their shot (else each starts its noise at its first frame).
"$NPRFX" synth orbit --frames 1-48 --size 160x90 --threads 2 -o plates/orbit.####.exr >/dev/null
cat >noise.json <<'EOF'
{
  "nodes": {
    "plate": {"node": "read", "path": "plates/orbit.####.exr"},
    "noise": {"node": "coherent-noise", "inputs": {"depth": "plate:Z", "motion_prev": "plate:motion_prev"},
              "params": {"alpha": 0.9, "output": "unit01", "contrast": 0.2}},
    "out": {"node": "write", "inputs": {"image": "noise"}, "path": "out/noise.####.exr"}
  }
}
EOF
# An override with a space and a quote, which the job files must pass through intact.
out_path="out/it's a noise.####.exr"
sets=(--set noise.seed=7 --set "out.path=$out_path")

# --- The job files.
expect_rc 0 "$NPRFX" farm noise.json --frames 1-48 --chunk 5 --emit jobs "${sets[@]}" \
    --cpus 2 --partition test --time 00:10:00
R=jobs/render.sbatch
for f in $R jobs/check.sbatch jobs/submit.sh; do
    [ -f "$f" ] || fail "$f not written"
    bash -n "$f" || fail "$f is not valid shell"
done
[ -d jobs/logs ] || fail "no logs directory (Slurm does not create it)"
[ -x jobs/submit.sh ] || fail "submit.sh is not executable"
has $R "#SBATCH --array=0-9"
has $R "#SBATCH --cpus-per-task=2"
has $R "#SBATCH --partition=test"
has $R "#SBATCH --time=00:10:00"
has $R "#SBATCH --output=$PWD/jobs/logs/chunk_%a.log"
has $R "#SBATCH --chdir=$PWD"
has $R "#SBATCH --requeue"
has $R '--threads "${SLURM_CPUS_PER_TASK:-1}"'
has $R " --shared-lock"
has $R " --shot 1-48 "
has $R " --set 'out.path=out/it'\\''s a noise.####.exr'"
has $R "$(readlink -f "$NPRFX") run $PWD/noise.json"
# The chunks as bash sees them: ten, of five frames, the last 46-48.
chunks=$(bash -c "$(grep '^chunks=' $R); echo \"\${#chunks[@]} \${chunks[0]} \${chunks[5]} \${chunks[9]}\"")
[ "$chunks" = "10 1-5 26-30 46-48" ] || fail "chunks are '$chunks'"
has jobs/check.sbatch "farm check $PWD/noise.json --frames 1-48 --shot 1-48 --set noise.seed=7"
has jobs/check.sbatch "#SBATCH --output=$PWD/jobs/logs/check.log"
has jobs/submit.sh "--dependency=afterany:\"\$render\""

# --- The chunks by hand, two at a time as on a farm, last first.
for pair in "9 8" "7 6" "5 4" "3 2" "1 0"; do
    pids=()
    for t in $pair; do
        SLURM_ARRAY_TASK_ID=$t SLURM_CPUS_PER_TASK=1 bash $R >"chunk$t.log" 2>&1 &
        pids+=($!)
    done
    for i in 0 1; do
        wait "${pids[$i]}" || { cat chunk*.log >&2; fail "a chunk of '$pair' failed"; }
    done
done
grep -q "warming up frames 1-" chunk5.log || grep -q "^frame 26 (1/5)" chunk5.log ||
    fail "chunk 5 did not render frames 26-30"
[ -z "$(ls -A out | grep nprfx-lock)" ] || fail "lock files left: $(ls -A out)"
[ "$(ls out | wc -l)" -eq 48 ] || fail "$(ls out | wc -l) frames written, expected 48"
# One sequential run of the same graph and overrides, its files under seq/.
expect_rc 0 "$NPRFX" run noise.json --frames 1-48 "${sets[@]}" --output-dir seq --threads 2 -q
expect_rc 0 "$NPRFX" diff "seq/$out_path" "$out_path" --frames 1-48 --fail 0 --warn 0
grep -qx PASS last.out || fail "chunked frames differ from the sequential run"
# The comparison can fail: a chunk run without the shot starts its noise at frame 26.
expect_rc 0 "$NPRFX" run noise.json --frames 26-30 "${sets[@]}" --output-dir alone --threads 2 -q
rc=0
"$NPRFX" diff "seq/$out_path" "alone/$out_path" --frames 26-30 --fail 0 --warn 0 -q >/dev/null || rc=$?
[ "$rc" -eq 2 ] || fail "a chunk without --shot matched the sequential run (diff exited $rc)"

# --- The locks: chunks share a sequence's lock; a plain run and a chunk exclude each other
# (flock(1) holds the lock, shared then exclusive, until the file 'release' appears).
lock="out/.it's a noise.####.exr.nprfx-lock"
rm -f held release
flock -s "$lock" sh -c 'touch held; until [ -e release ]; do sleep 0.05; done' &
holder=$!
until [ -e held ]; do sleep 0.05; done
expect_rc 2 "$NPRFX" run noise.json --frames 3 "${sets[@]}" --shot 1-48 -q
has last.err "is being written by another run"
expect_rc 0 "$NPRFX" run noise.json --frames 3 "${sets[@]}" --shot 1-48 -q --shared-lock
touch release
wait $holder
rm -f held release
flock "$lock" sh -c 'touch held; until [ -e release ]; do sleep 0.05; done' &
holder=$!
until [ -e held ]; do sleep 0.05; done
expect_rc 2 "$NPRFX" run noise.json --frames 3 "${sets[@]}" --shot 1-48 -q --shared-lock
has last.err "is being written by another run"
touch release
wait $holder
rm -f "$lock"

# --- farm check: complete, then a frame deleted, one truncated, a killed chunk's temporary file.
expect_rc 0 "$NPRFX" farm check noise.json --frames 1-48 --shot 1-48 "${sets[@]}"
has last.out "all 48 frames complete"
rm "out/it's a noise.0007.exr"
head -c 2000 "seq/out/it's a noise.0040.exr" >"out/it's a noise.0040.exr"
echo partial >"out/.it's a noise.0012.tmp-999-0.exr"
expect_rc 1 bash jobs/check.sbatch
has last.out "frame 7: out/it's a noise.0007.exr: missing"
has last.out "frame 40: out/it's a noise.0040.exr: damaged:"
grep -c "re-render: cd $PWD && " last.out | grep -qx 2 || fail "not one re-render command a frame"
has last.out " --shot 1-48 --set noise.seed=7 --set 'out.path=out/it'\\''s a noise.####.exr' --frames 7-7"
has last.out " --frames 40-40"
has last.out "2 of 48 frames missing or damaged (7,40)"
has last.err "removed 1 temporary file"
[ ! -e "out/.it's a noise.0012.tmp-999-0.exr" ] || fail "the killed chunk's temporary file is left"
# The command it prints renders them again, and the sequence is then whole and exact.
again=$(grep -A1 "to render them all again" last.out | tail -1)
eval "$again" >/dev/null 2>&1 || fail "the re-render command failed: $again"
expect_rc 0 "$NPRFX" farm check noise.json --frames 1-48 --shot 1-48 "${sets[@]}"
expect_rc 0 "$NPRFX" diff "seq/$out_path" "$out_path" --frames 1-48 --fail 0 --warn 0 -q

# --- --submit through a stand-in sbatch: the array first, the check after it (afterany).
mkdir -p fakebin
cat >fakebin/sbatch <<EOF
#!/bin/sh
echo "\$*" >>"$PWD/sbatch.calls"
n=\$(wc -l <"$PWD/sbatch.calls")
echo "\$((100 + n));cluster"
EOF
chmod +x fakebin/sbatch
PATH="$PWD/fakebin:$PATH" expect_rc 0 "$NPRFX" farm noise.json --frames 1-48 --chunk 5 --submit
has last.out "render job: 101 (10 chunks)"
has last.out "check job: 102"
[ "$(sed -n 1p sbatch.calls)" = "--parsable $PWD/nprfx-farm.noise/render.sbatch" ] ||
    fail "first sbatch call: $(sed -n 1p sbatch.calls)"
[ "$(sed -n 2p sbatch.calls)" = "--parsable --dependency=afterany:101 $PWD/nprfx-farm.noise/check.sbatch" ] ||
    fail "second sbatch call: $(sed -n 2p sbatch.calls)"

# --- Bad requests: a clear error, status 2, nothing written or submitted.
mkdir -p empty
bad() {
    local want=$1
    shift
    expect_rc 2 "$@"
    grep -qF -- "$want" last.err || { cat last.err >&2; fail "'$*': no '$want' in the message"; }
    [ ! -e badjobs ] || fail "'$*' wrote job files"
}
bad "unknown engine 'pbs' (known: slurm)" "$NPRFX" farm noise.json --chunk 5 --engine pbs --emit badjobs
bad "--chunk must be a whole number of frames >= 1, not '0'" "$NPRFX" farm noise.json --chunk 0 --emit badjobs
bad "not '-5'" "$NPRFX" farm noise.json --chunk -5 --emit badjobs
bad "not '2.5'" "$NPRFX" farm noise.json --chunk 2.5 --emit badjobs
bad "not 'many'" "$NPRFX" farm noise.json --chunk many --emit badjobs
bad "read node 'plate' cannot read 'plates/orbit.0049.exr' (frame 49)" \
    "$NPRFX" farm noise.json --frames 1-60 --chunk 5 --emit badjobs
has last.err "12 of 60 frames lack their file"
sed 's/"nodes"/"frames": "1-48", "nodes"/' noise.json >declared.json
bad "frame 49 is outside the graph's frames 1-48" \
    "$NPRFX" farm declared.json --frames 40-50 --chunk 5 --emit badjobs
bad "sbatch is not on PATH" env PATH="$PWD/empty" "$NPRFX" farm noise.json --chunk 5 --submit
[ ! -e nprfx-farm.noise/logs/x ] && [ "$(wc -l <sbatch.calls)" -eq 2 ] || fail "sbatch ran"
bad "say --submit" "$NPRFX" farm noise.json --chunk 5
bad "no node 'nosuch'" "$NPRFX" farm noise.json --chunk 5 --set nosuch.seed=1 --emit badjobs
expect_rc 2 "$NPRFX" farm check noise.json --frames 1-x
echo "farm: all checks passed"
