# nprfx farm on a real farm: a single-node Slurm cluster on this machine (munged,
# slurmctld and slurmd started here, their config and state in the work directory, no accounting),
# 48 frames of a coherent-noise graph submitted in chunks of 5 with --submit, the array and the
# check job waited for, every frame compared exactly with one sequential `nprfx run`.
# Needs root and Debian's slurm-wlm (.ci/setup installs it); otherwise, or when the daemons cannot
# start here, it prints why and exits 77, which ctest reports as skipped.
# usage: bash farm_slurm.sh NPRFX SOURCE_DIR WORK_DIR
set -eu
NPRFX=$1
WORK=$3
SKIP=77
skip() {
    echo "SKIPPED: $*"
    exit $SKIP
}
fail() {
    echo "FAIL: $*" >&2
    exit 1
}

[ "$(id -u)" = 0 ] || skip "not root: a test cluster's slurmd runs jobs as their users and needs root"
for tool in munged slurmctld slurmd sbatch squeue sinfo scontrol; do
    command -v "$tool" >/dev/null || PATH=$PATH:/usr/sbin:/sbin
    command -v "$tool" >/dev/null ||
        skip "$tool not found: install Debian's slurm-wlm (bash .ci/setup does)"
done

rm -rf "$WORK"
mkdir -p "$WORK"
cd "$WORK"
W=$PWD
C=$W/cluster
mkdir -p "$C/state" "$C/spool"
chmod 700 "$C"

pids=()
stop_daemons() {
    # The jobs first (slurmd would leave their steps running), then the daemons, whatever happened.
    [ -f "$C/slurm.conf" ] && SLURM_CONF=$C/slurm.conf scancel --quiet --user=root 2>/dev/null || true
    for pid in "${pids[@]}"; do
        kill "$pid" 2>/dev/null || true
    done
    for pid in "${pids[@]}"; do
        for _ in $(seq 50); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
        kill -9 "$pid" 2>/dev/null || true
    done
    # what slurmd mounted under the test's folder
    for m in $(awk -v d="$C/cgroup/" 'index($2, d) == 1 {print $2}' /proc/mounts 2>/dev/null); do
        umount "$m" 2>/dev/null || true
    done
}
trap stop_daemons EXIT
trap 'exit 1' INT TERM

# munge: its own key, socket and files here; --force because it runs as root.
dd if=/dev/urandom of="$C/munge.key" bs=1024 count=1 status=none
chmod 400 "$C/munge.key"
munged -F --force --key-file="$C/munge.key" --socket="$C/munge.sock" --pid-file="$C/munged.pid" \
    --log-file="$C/munged.log" --seed-file="$C/munged.seed" >"$C/munged.out" 2>&1 &
pids+=($!)
for _ in $(seq 50); do [ -S "$C/munge.sock" ] && break; sleep 0.1; done
[ -S "$C/munge.sock" ] || skip "munged did not start here: $(tail -3 "$C/munged.log" "$C/munged.out" 2>/dev/null | tr '\n' ' ')"

# Slurm: this host as controller and only node, 2 CPUs (fewer when the machine has fewer), ports
# of its own so that another cluster on the machine is left alone.
host=$(hostname -s)
cpus=$(nproc)
[ "$cpus" -gt 2 ] && cpus=2
port=$((20000 + $$ % 20000 * 2))
cat >"$C/slurm.conf" <<EOF
ClusterName=nprfxtest
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=$port
SlurmdPort=$((port + 1))
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$C/munge.sock
MpiDefault=none
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
AccountingStorageType=accounting_storage/none
JobAcctGatherType=jobacct_gather/none
JobCompType=jobcomp/none
ReturnToService=2
StateSaveLocation=$C/state
SlurmdSpoolDir=$C/spool
SlurmctldPidFile=$C/slurmctld.pid
SlurmdPidFile=$C/slurmd.pid
SlurmctldLogFile=$C/slurmctld.log
SlurmdLogFile=$C/slurmd.log
SlurmctldDebug=info
SlurmdDebug=info
SchedulerType=sched/backfill
SchedulerParameters=sched_interval=1
MinJobAge=600
NodeName=$host NodeAddr=127.0.0.1 CPUs=$cpus State=UNKNOWN
PartitionName=test Nodes=$host Default=YES MaxTime=INFINITE State=UP
EOF
# slurmd 22.05 starts its cgroup plugin whatever the proctrack and task plugins use; a build root
# or container with no cgroup file system at /sys/fs/cgroup (a CI's fresh Debian root) lets it
# mount the v1 controllers under the test's own folder instead
if [ ! -e /sys/fs/cgroup/cgroup.controllers ] && [ ! -d /sys/fs/cgroup/freezer ]; then
    mkdir -p "$C/cgroup"
    printf 'CgroupPlugin=cgroup/v1\nCgroupMountpoint=%s\nCgroupAutomount=yes\n' "$C/cgroup" \
        >"$C/cgroup.conf"
fi
export SLURM_CONF=$C/slurm.conf
slurmctld -D -i -f "$C/slurm.conf" >"$C/slurmctld.out" 2>&1 &
pids+=($!)
slurmd -D -f "$C/slurm.conf" -N "$host" >"$C/slurmd.out" 2>&1 &
pids+=($!)
state=
for _ in $(seq 150); do
    state=$(sinfo -h -n "$host" -o %T 2>/dev/null || true)
    [ "$state" = idle ] && break
    for pid in "${pids[@]}"; do kill -0 "$pid" 2>/dev/null || break 2; done
    sleep 0.2
done
if [ "$state" != idle ]; then
    # (some logs may not exist: a daemon that died at once; tail's status must not end the test)
    tail -n 8 "$C"/*.log "$C"/*.out 2>/dev/null || true
    skip "the test cluster did not come up here (node state '$state'; the daemons' logs are above)"
fi
echo "test cluster up: node $host, $cpus CPUs, port $port"

# 48 frames of plates and the graph; the shot is rendered on the cluster, in chunks of 5.
"$NPRFX" synth orbit --frames 1-48 --size 320x180 --threads 2 -o plates/orbit.####.exr >/dev/null
cat >noise.json <<'EOF'
{
  "frames": "1-48",
  "nodes": {
    "plate": {"node": "read", "path": "plates/orbit.####.exr"},
    "noise": {"node": "coherent-noise", "inputs": {"depth": "plate:Z", "motion_prev": "plate:motion_prev"},
              "params": {"alpha": 0.9, "output": "unit01", "contrast": 0.2}},
    "out": {"node": "write", "inputs": {"image": "noise"}, "path": "out/noise.####.exr"}
  }
}
EOF
t0=$(date +%s.%N)
"$NPRFX" farm noise.json --frames 1-48 --chunk 5 --cpus 1 --submit --emit jobs \
    --set noise.seed=7 >submit.out || { cat submit.out; fail "nprfx farm --submit failed"; }
cat submit.out
render=$(sed -n 's/^render job: \([0-9]*\).*/\1/p' submit.out)
check=$(sed -n 's/^check job: \([0-9]*\)$/\1/p' submit.out)
[ -n "$render" ] && [ -n "$check" ] || fail "no job ids in the output of --submit"

# Wait for both jobs to leave the queue (3 minutes at most), then read their outcomes.
for _ in $(seq 900); do
    [ -z "$(squeue -h -j "$render,$check" -o %i 2>/dev/null)" ] && break
    sleep 0.2
done
t1=$(date +%s.%N)
[ -z "$(squeue -h -j "$render,$check" -o %i 2>/dev/null)" ] ||
    { squeue; tail -5 "$C/slurmctld.log"; fail "the jobs did not finish within 3 minutes"; }
scontrol show job "$render" >render.state || true
scontrol show job "$check" >check.state
tasks=$(grep -c "JobState=COMPLETED" render.state || true)
[ "$tasks" -eq 10 ] || { cat render.state jobs/logs/chunk_*.log; fail "$tasks of 10 chunks completed"; }
grep -q "JobState=COMPLETED" check.state || { cat check.state jobs/logs/check.log; fail "the check job failed"; }
grep -q "all 48 frames complete" jobs/logs/check.log || fail "check log: $(cat jobs/logs/check.log)"
grep -q "frames 46-48" jobs/logs/chunk_9.log || fail "chunk 9 did not render frames 46-48"

# One sequential run on this machine, every frame compared exactly.
t2=$(date +%s.%N)
"$NPRFX" run noise.json --frames 1-48 --set noise.seed=7 --output-dir seq --threads 2 -q
t3=$(date +%s.%N)
"$NPRFX" diff 'seq/out/noise.####.exr' 'out/noise.####.exr' --frames 1-48 --fail 0 --warn 0 -q \
    >diff.out || { cat diff.out; fail "frames rendered on the cluster differ from one run"; }
grep -qx PASS diff.out || fail "diff: $(cat diff.out)"
awk -v a="$t0" -v b="$t1" -v c="$t2" -v d="$t3" 'BEGIN {
    printf "48 frames at 320x180: one run (2 threads) %.1f s; 10 chunks of 5 on the cluster (1 CPU each, 2 at a time, submit to check job done) %.1f s\n", d - c, b - a }'
echo "farm_slurm: all checks passed"
