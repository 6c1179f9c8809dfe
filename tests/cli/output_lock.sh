# Output sequence locks (cli/util/output_lock.c): a second run on a sequence another run is writing
# fails at once naming that run and the path, or waits for it with --wait; a run killed with
# kill -9 leaves no stale lock, and the next run removes the temporary files it left (only
# those). The first run is stopped (SIGSTOP) once it holds its lock, so the overlap does not
# depend on timing; it then goes on with SIGCONT.
# usage: bash output_lock.sh NPRFX SOURCE_DIR WORK_DIR
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
# graph NAME OPACITY FRAMES OUT: a blend of the orbit scene written to OUT/x.####.exr with PNG
# previews; graphs of different OPACITY write different frames.
graph() {
    cat >"$1.json" <<EOF
{"frames": "$3", "nodes": {
  "plate": {"node": "synth", "scene": "orbit", "size": "320x240"},
  "b": {"node": "blend", "inputs": {"base": "plate:R,G,B", "layer": "plate:diffuse"},
        "params": {"mode": "multiply", "opacity": $2}},
  "w": {"node": "write", "inputs": {"image": "b"}, "path": "$4/x.####.exr",
        "preview": "$4/x.####.png"}}}
EOF
}
LOCK='o/.x.####.exr.nprfx-lock'
# wait_for FILE PID: until FILE exists (while PID runs; 20 s at most).
wait_for() {
    for _ in $(seq 400); do
        [ -e "$1" ] && return 0
        kill -0 "$2" 2>/dev/null || fail "the run ended before '$1' appeared"
        sleep 0.05
    done
    fail "'$1' never appeared"
}
# same_frames DIR_A DIR_B N: frames 1-N of both are there and identical (EXR pixels: the
# header holds the time of writing; PNG bytes).
same_frames() {
    for f in $(seq -f %04g 1 "$3"); do
        cmp -s "$1/x.$f.png" "$2/x.$f.png" || fail "$2/x.$f.png differs from $1's"
    done
    "$NPRFX" diff "$1/x.####.exr" "$2/x.####.exr" --frames "1-$3" --fail 0 --warn 0 >/dev/null ||
        fail "the frames of $2/x.####.exr differ from $1's"
}
no_temp_files() {
    local left
    left=$(find o -regextype posix-extended -regex '.*/\.x\.[0-9]{4}\.tmp-[0-9]+-[0-9]+\.(exr|png)')
    [ -z "$left" ] || fail "temporary files left: $left"
}

N=6
graph a 1 "1-$N" o
graph b 0.3 "1-$N" o
graph ref_a 1 "1-$N" ref_a
graph ref_b 0.3 "1-$N" ref_b
"$NPRFX" run ref_a.json ref_b.json --quiet

# 1. A second run while the first holds the sequence fails at once, naming the run and path.
"$NPRFX" run a.json --quiet --threads 1 &
pid=$!
wait_for "$LOCK" $pid
kill -STOP $pid
grep -q "^pid=$pid$" "$LOCK" || fail "the lock file does not name pid $pid: $(cat "$LOCK")"
rc=0
"$NPRFX" run b.json --quiet 2>b.err || rc=$?
[ $rc -eq 2 ] || fail "the second run exited $rc, expected 2: $(cat b.err)"
grep -qF "'o/x.####.exr' is being written by another run (pid $pid on host " b.err ||
    fail "the refusal does not name the path and pid $pid: $(cat b.err)"
grep -qF "a.json" b.err || fail "the refusal does not name the other graph: $(cat b.err)"
grep -qF -- "--wait" b.err || fail "the refusal does not mention --wait: $(cat b.err)"
# The same sequence spelled %04d under --output-dir locks the same file.
rc=0
"$NPRFX" run b.json --quiet --output-dir . --set 'w.path=o/x.%04d.exr' 2>b.err || rc=$?
[ $rc -eq 2 ] && grep -qF "pid $pid" b.err || fail "%04d spelling not refused: $rc $(cat b.err)"
kill -CONT $pid
wait $pid || fail "the first run failed"
same_frames ref_a o $N
[ ! -e "$LOCK" ] || fail "the lock file outlived its run"

# 2. --wait: the second run waits, then writes the whole sequence itself.
"$NPRFX" run a.json --quiet --threads 1 &
pid=$!
wait_for "$LOCK" $pid
kill -STOP $pid
"$NPRFX" run b.json --wait 2>b.err >/dev/null &
pid_b=$!
for _ in $(seq 400); do
    grep -qF "waiting for another run" b.err && break
    kill -0 $pid_b 2>/dev/null || fail "the second run did not wait: $(cat b.err)"
    sleep 0.05
done
grep -qF "waiting for another run writing 'o/x.####.exr' (pid $pid" b.err ||
    fail "the waiting run did not say whom it waits for: $(cat b.err)"
kill -CONT $pid
wait $pid || fail "the first run failed"
wait $pid_b || fail "the waiting run failed: $(cat b.err)"
same_frames ref_b o $N
no_temp_files

# 3. kill -9 mid-way: no stale lock, and the rerun removes the temporary files of its sequence
# (a planted one from a dead pid too) but nothing that merely looks like one.
rm -rf o
"$NPRFX" run a.json --quiet --threads 1 &
pid=$!
wait_for o/x.0001.png $pid
kill -9 $pid
wait $pid 2>/dev/null || true
[ -e "$LOCK" ] || fail "expected the killed run's lock file to remain"
touch o/.x.0005.tmp-999999-3.exr o/.x.0005.tmp-999999-4.png
touch o/.x.0005.tmp-1-0.exr.bak o/x.0005.tmp-1-0.exr o/.y.0005.tmp-1-0.exr o/.x.05.tmp-1-0.exr
"$NPRFX" run a.json 2>a.err >/dev/null || fail "the rerun after kill -9 failed: $(cat a.err)"
grep -q "removed [0-9]* temporary files\? of 'o/x.####.exr' left by an interrupted run" a.err ||
    fail "the rerun did not report removing temporary files: $(cat a.err)"
no_temp_files
for keep in .x.0005.tmp-1-0.exr.bak x.0005.tmp-1-0.exr .y.0005.tmp-1-0.exr .x.05.tmp-1-0.exr; do
    [ -e "o/$keep" ] || fail "the rerun removed o/$keep, which is not its temporary file"
done
same_frames ref_a o $N
[ ! -e "$LOCK" ] || fail "the lock file outlived the rerun"
echo "output_lock: ok"
