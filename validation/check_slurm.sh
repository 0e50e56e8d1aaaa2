#!/usr/bin/env bash
# `baker slurm` on a real Slurm scheduler: Debian's slurm-wlm (22.05 on bookworm) and munge,
# one controller and one compute node on this machine.
#
# 1. Installs slurm-wlm and munge with apt (skipped where they are installed), starts munged,
#    writes a single-node /etc/slurm/slurm.conf (the node line comes from `slurmd -C`) and starts
#    slurmctld and slurmd, without systemd.
# 2. Smoke test of the scheduler alone: a 2-task array job and a job depending on it (afterok).
# 3. Bakes a small skin spec (tests/specs/profiles_small.yaml) and a small fiber spec (two
#    polyester fibers, 30° bins) twice: locally with `baker bake`, and with
#    `baker slurm --shards 4 --submit`, i.e. a 4-task array job of `baker bake --shard I/4` and a
#    dependent `baker merge`. Every job must exit 0 and the two output trees must be identical,
#    byte for byte (differing files are named; JSON ones with the differing keys).
#
# The daemons it started are stopped on exit (--keep leaves them running for `sinfo`, `squeue`,
# `sbatch`). Run it as root on Debian; running it again is fine. It refuses to overwrite a
# slurm.conf or cgroup.conf it did not write.
#
#   bash validation/check_slurm.sh --baker target/release/baker
#
# About a minute on 2 cores once the packages are installed.
set -euo pipefail

ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
BAKER=$ROOT/target/release/baker
SHARDS=4
PHOTONS=2000
TIMEOUT=600
KEEP=0
WORK=
usage() {
    sed -n '2,/^set -euo/p' "${BASH_SOURCE[0]}" | sed '$d; s/^# \{0,1\}//'
    echo "options: --baker PATH  --shards N (4)  --photons N (2000)  --timeout SECONDS (600)"
    echo "         --work DIR (default: a new temporary directory)  --keep (leave the daemons running)"
}
while [[ $# -gt 0 ]]; do
    case $1 in
    --baker) BAKER=$2; shift 2 ;;
    --shards) SHARDS=$2; shift 2 ;;
    --photons) PHOTONS=$2; shift 2 ;;
    --timeout) TIMEOUT=$2; shift 2 ;;
    --work) WORK=$2; shift 2 ;;
    --keep) KEEP=1; shift ;;
    -h | --help) usage; exit 0 ;;
    *) echo "check_slurm: unknown argument $1" >&2; usage >&2; exit 2 ;;
    esac
done

say() { printf '== %s\n' "$*"; }
die() { printf 'check_slurm: FAIL: %s\n' "$*" >&2; exit 1; }

[[ $(id -u) -eq 0 ]] || die "run as root (it installs packages and starts the Slurm daemons)"
[[ -x $BAKER ]] || die "no baker binary at $BAKER (cargo build --release -p baker)"
BAKER=$(realpath "$BAKER")
"$BAKER" slurm --help >/dev/null 2>&1 || die "$BAKER has no 'slurm' command"
"$BAKER" merge --help >/dev/null 2>&1 || die "$BAKER has no 'merge' command"
TEMP_WORK=0
if [[ -z $WORK ]]; then
    WORK=$(mktemp -d /tmp/check_slurm.XXXXXX)
    TEMP_WORK=1
else
    mkdir -p "$WORK"
    WORK=$(realpath "$WORK")
    rm -rf "$WORK/local" "$WORK/slurm" "$WORK/slurm-out" "$WORK/smoke" "$WORK/specs"
fi

# Everything the daemons keep, in directories of their own (wiped on every run).
CONF=/etc/slurm/slurm.conf
CGROUP_CONF=/etc/slurm/cgroup.conf
MARK="# Written by baker's validation/check_slurm.sh; it rewrites this file on every run."
STATE=/var/spool/baker-slurm
LOGS=/var/log/baker-slurm
RUN=/run/baker-slurm
JOBCOMP=$LOGS/jobcomp.log
NODE=$(hostname -s)

# --- 1. packages, munge, Slurm ----------------------------------------------------------------

if ! command -v slurmctld >/dev/null || ! command -v slurmd >/dev/null ||
    ! command -v sbatch >/dev/null || ! command -v munged >/dev/null; then
    say "installing slurm-wlm and munge"
    export DEBIAN_FRONTEND=noninteractive
    apt-get update -qq
    apt-get install -y -qq --no-install-recommends slurm-wlm munge >/dev/null
fi
say "$(slurmctld -V), $(munged --version 2>&1 | awk '{print $1; exit}')"

# Stops the process in pid file $1 if it is still the program $2 (pid files outlive crashes).
stop_pidfile() {
    local file=$1 name=$2 pid
    [[ -s $file ]] || return 0
    pid=$(<"$file")
    if [[ $(cat "/proc/$pid/comm" 2>/dev/null) == "$name" ]]; then
        kill "$pid" 2>/dev/null || true
        for _ in $(seq 100); do
            [[ -d /proc/$pid ]] || break
            sleep 0.1
        done
        if [[ -d /proc/$pid ]]; then kill -9 "$pid" 2>/dev/null || true; fi
    fi
    rm -f "$file"
}

STARTED_MUNGED=0
cleanup() {
    local rc=$?
    if [[ $KEEP == 1 ]]; then
        say "--keep: slurmctld, slurmd$([[ $STARTED_MUNGED == 1 ]] && echo ", munged") left running"
    else
        stop_pidfile "$RUN/slurmd.pid" slurmd
        stop_pidfile "$RUN/slurmctld.pid" slurmctld
        [[ $STARTED_MUNGED == 1 ]] && stop_pidfile /run/munge/munged.pid munged
    fi
    if [[ $rc -ne 0 ]]; then
        echo "check_slurm: daemon logs in $LOGS, job logs in $WORK" >&2
    elif [[ $TEMP_WORK == 1 && $KEEP == 0 ]]; then
        rm -rf "$WORK"
    fi
    exit $rc
}
trap cleanup EXIT

# Munge authenticates every Slurm message. The Debian package creates the key at install time;
# a machine where it is missing gets a new one.
if [[ ! -s /etc/munge/munge.key ]]; then
    say "creating /etc/munge/munge.key"
    if command -v mungekey >/dev/null; then
        mungekey --create --keyfile=/etc/munge/munge.key --force
    else
        dd if=/dev/urandom of=/etc/munge/munge.key bs=1024 count=1 status=none
    fi
fi
chown munge:munge /etc/munge/munge.key
chmod 400 /etc/munge/munge.key
if ! munge -n 2>/dev/null | unmunge >/dev/null 2>&1; then
    say "starting munged"
    mkdir -p /run/munge /var/log/munge /var/lib/munge
    chown munge:munge /run/munge /var/log/munge /var/lib/munge
    chmod 755 /run/munge
    runuser -u munge -- /usr/sbin/munged
    STARTED_MUNGED=1
    for _ in $(seq 50); do
        munge -n 2>/dev/null | unmunge >/dev/null 2>&1 && break
        sleep 0.1
    done
    munge -n | unmunge >/dev/null || die "munged does not answer (see /var/log/munge/munged.log)"
fi

for f in "$CONF" "$CGROUP_CONF"; do
    if [[ -e $f ]] && [[ $(head -n 1 "$f") != "$MARK" ]]; then
        die "$f exists and was not written by this script; refusing to overwrite it"
    fi
done

# A previous run that was killed may have left its daemons behind.
stop_pidfile "$RUN/slurmd.pid" slurmd
stop_pidfile "$RUN/slurmctld.pid" slurmctld
rm -rf "$STATE" "$LOGS"
mkdir -p "$STATE/ctld" "$STATE/d" "$LOGS" "$RUN"

# `slurmd -C`: this node as slurmd sees it (CPUs, sockets, cores, threads, RealMemory).
NODE_LINE=$(slurmd -C | head -n 1)
[[ $NODE_LINE == NodeName=$NODE\ * ]] || die "slurmd -C printed '$NODE_LINE', expected NodeName=$NODE"
cat >"$CONF" <<EOF
$MARK
# One controller and one compute node on this machine, no accounting database, no systemd.
ClusterName=baker-check
SlurmctldHost=$NODE(127.0.0.1)
SlurmUser=root
AuthType=auth/munge
MpiDefault=none
# No cgroups: processes are tracked through /proc, tasks are not confined.
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
# Without slurmdbd, sacct has nothing; every finished job's state and exit code go here.
JobCompType=jobcomp/filetxt
JobCompLoc=$JOBCOMP
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
SchedulerType=sched/backfill
ReturnToService=2
# Finished jobs stay visible to scontrol for 10 minutes.
MinJobAge=600
StateSaveLocation=$STATE/ctld
SlurmdSpoolDir=$STATE/d
SlurmctldPidFile=$RUN/slurmctld.pid
SlurmdPidFile=$RUN/slurmd.pid
SlurmctldLogFile=$LOGS/slurmctld.log
SlurmdLogFile=$LOGS/slurmd.log
$NODE_LINE NodeAddr=127.0.0.1 State=UNKNOWN
PartitionName=debug Nodes=$NODE Default=YES MaxTime=INFINITE State=UP
EOF

say "starting slurmctld"
slurmctld || die "slurmctld did not start: $(tail -n 5 "$LOGS/slurmctld.log" 2>/dev/null)"
for _ in $(seq 100); do
    scontrol ping 2>/dev/null | grep -q UP && break
    sleep 0.1
done
scontrol ping | grep -q UP || die "slurmctld does not answer: $(tail -n 5 "$LOGS/slurmctld.log")"

# slurmd (22.05) always loads a cgroup plugin, even with proctrack/linuxproc and task/none
# ("CgroupPlugin=disabled" only came with 23.02). Autodetection works with cgroup v1 and with
# systemd; a cgroup v2 container without systemd needs IgnoreSystemd. Try each in turn.
cgroup_variants=("" $'CgroupPlugin=cgroup/v2\nIgnoreSystemd=yes\nCgroupAutomount=yes' "CgroupPlugin=cgroup/v1")
started=0
for variant in "${cgroup_variants[@]}"; do
    if [[ -n $variant ]]; then
        printf '%s\n%s\n' "$MARK" "$variant" >"$CGROUP_CONF"
    else
        rm -f "$CGROUP_CONF"
    fi
    desc=${variant:-CgroupPlugin=autodetect}
    if slurmd 2>>"$LOGS/slurmd-start.log"; then
        # It forks before some of its initialisation: it must still be there.
        sleep 1
        if [[ -s $RUN/slurmd.pid ]] && [[ -d /proc/$(<"$RUN/slurmd.pid") ]]; then
            say "slurmd started (cgroup.conf: ${desc//$'\n'/, })"
            started=1
            break
        fi
    fi
    echo "slurmd failed with cgroup.conf: ${desc//$'\n'/, }" >&2
    tail -n 4 "$LOGS/slurmd.log" >&2 2>/dev/null || true
done
[[ $started == 1 ]] || die "slurmd did not start with any cgroup set-up (see $LOGS/slurmd.log)"

# Wait for the node to register and be idle; a node remembered as down is resumed.
state=
for _ in $(seq 120); do
    state=$(sinfo -h -n "$NODE" -o %T 2>/dev/null || true)
    case $state in
    idle) break ;;
    down* | drain* | fail*) scontrol update nodename="$NODE" state=resume 2>/dev/null || true ;;
    esac
    sleep 0.5
done
[[ $state == idle ]] || die "node $NODE is '$state', not idle: $(scontrol show node "$NODE" | grep -i reason)"
sinfo

# --- job helpers ---------------------------------------------------------------------------------

# Waits until none of the given jobs is queued or running.
wait_jobs() {
    local ids=$1 left t0=$SECONDS
    while :; do
        left=$(squeue -h -j "$ids" -o '%i %T %r' 2>/dev/null || true)
        [[ -z $left ]] && return 0
        if ((SECONDS - t0 > TIMEOUT)); then
            echo "$left" >&2
            die "jobs $ids still queued or running after ${TIMEOUT}s"
        fi
        sleep 1
    done
}

# The jobcomp records of job $1 (with --array, of every task of array job $1).
job_records() {
    if [[ ${2:-} == --array ]]; then
        grep -E "(^| )ArrayJobId=$1 " "$JOBCOMP" || true
    else
        grep -E "^JobId=$1 " "$JOBCOMP" || true
    fi
}

# Checks that job $2 (array job with --array, $3 tasks) finished, every task COMPLETED with exit
# code 0; $1 names it.
check_job() {
    local what=$1 id=$2 flag=${3:-} want=${4:-1} records n ok
    # The completion record is written just after the job leaves the queue.
    for _ in $(seq 50); do
        records=$(job_records "$id" "$flag")
        n=$(printf '%s' "$records" | grep -c . || true)
        ((n >= want)) && break
        sleep 0.2
    done
    ok=$(printf '%s\n' "$records" | grep -c 'JobState=COMPLETED .*ExitCode=0:0' || true)
    if [[ $n -ne $want || $ok -ne $want ]]; then
        echo "   $what: job $id, $ok of $want completed with exit code 0:" >&2
        printf '%s\n' "$records" | awk '{
            o = ""
            for (i = 1; i <= NF; i++) if ($i ~ /^(JobId|ArrayTaskId|JobState|ExitCode)=/) o = o " " $i
            print "    " o
        }' >&2
        return 1
    fi
    echo "   $what: job $id, $want of $want completed with exit code 0"
}

# --- 2. the scheduler alone ------------------------------------------------------------------------

say "smoke test: a 2-task array job, and a job after it (afterok)"
mkdir -p "$WORK/smoke"
# shellcheck disable=SC2016 # expanded by the job, not here
a=$(sbatch --parsable --array=1-2 --output="$WORK/smoke/task-%a.log" \
    --wrap 'echo "task $SLURM_ARRAY_TASK_ID of job $SLURM_ARRAY_JOB_ID on $(hostname -s)"')
a=${a%%;*}
b=$(sbatch --parsable --dependency=afterok:"$a" --output="$WORK/smoke/after.log" \
    --wrap 'echo after; cat task-*.log' --chdir="$WORK/smoke")
b=${b%%;*}
wait_jobs "$a,$b"
check_job "array" "$a" --array 2 || die "smoke array job $a failed"
check_job "dependent job" "$b" || die "smoke dependent job $b failed"
grep -q "task 2 of job $a" "$WORK/smoke/after.log" || die "the dependent job ran before the array job"

# --- 3. a bake, local and on Slurm -----------------------------------------------------------------

mkdir -p "$WORK/specs"
FIBER_SPEC=$WORK/specs/fibers_tiny.yaml
cat >"$FIBER_SPEC" <<'EOF'
# Two polyester fibers, 30° bins, few photons: a fiber bake of a few seconds (check_slurm.sh).
version: 1
bake: {resolution_deg: 30, photons_per_direction: 2048, seed: 3}
fibers:
  - {name: polyester, type: polyester, section: {shape: circle}, dye: disperse_red_1, depth_of_shade_percent: 1.0}
  - {name: polyester_trilobal, type: polyester, section: {shape: trilobal}, dye: disperse_red_1, depth_of_shade_percent: 1.0}
EOF
# The spec paths are recorded in the outputs: both bakes get the same strings, from the same
# directory (`baker slurm` runs its jobs where it was called).
cd "$ROOT"
SPECS=(tests/specs/profiles_small.yaml "$FIBER_SPEC")

say "local bake: baker bake ${SPECS[*]} --photons $PHOTONS"
t0=$SECONDS
"$BAKER" bake "${SPECS[@]}" --out "$WORK/local" --photons "$PHOTONS" --quiet
echo "   $((SECONDS - t0)) s"

say "Slurm bake: baker slurm ${SPECS[*]} --shards $SHARDS --submit -- --photons $PHOTONS"
t0=$SECONDS
submitted=$("$BAKER" slurm "${SPECS[@]}" --shards "$SHARDS" --partition debug --time 10 \
    --work "$WORK/slurm" --out "$WORK/slurm-out" --submit -- --photons "$PHOTONS")
printf '%s\n' "$submitted" | sed 's/^/   /'
array=$(printf '%s\n' "$submitted" | awk '/^bake array job /{print $4}')
merge=$(printf '%s\n' "$submitted" | awk '/^merge job /{print $3}')
[[ $array =~ ^[0-9]+$ && $merge =~ ^[0-9]+$ ]] || die "no job ids in the output of baker slurm --submit"
wait_jobs "$array,$merge"
echo "   $((SECONDS - t0)) s"
jobs_ok=1
check_job "shards" "$array" --array "$SHARDS" || jobs_ok=0
check_job "merge" "$merge" || jobs_ok=0
if [[ $jobs_ok == 0 ]]; then
    for log in "$WORK"/slurm/logs/*.log; do
        echo "--- $log (last lines)" >&2
        tail -n 8 "$log" >&2
    done
    die "a Slurm job of the bake did not complete with exit code 0"
fi
for i in $(seq "$SHARDS"); do
    [[ -s $WORK/slurm/logs/shard-$i.log ]] || die "shard $i wrote no log"
    [[ -s $WORK/slurm/shard-$i/shard.json ]] || die "shard $i wrote no shard.json"
done
# The work was split: every shard baked units of its own.
python3 - "$WORK/slurm" "$SHARDS" <<'PY' || die "a shard baked no work unit"
import json, sys
counts = [len(json.load(open(f"{sys.argv[1]}/shard-{i}/shard.json"))["units"])
          for i in range(1, int(sys.argv[2]) + 1)]
print(f"   work units per shard: {' '.join(map(str, counts))}")
sys.exit(0 if all(counts) else 1)
PY

# The products: OUT/<spec name>/ for each spec (OUT/.cache, the unit cache, is not compared).
STEMS=(profiles_small fibers_tiny)
say "comparing $WORK/slurm-out with $WORK/local, byte for byte: ${STEMS[*]}"
n_local=0
n_slurm=0
: >"$WORK/diff.txt"
for stem in "${STEMS[@]}"; do
    [[ -d $WORK/local/$stem ]] || die "the local bake wrote no $WORK/local/$stem"
    n_local=$((n_local + $(find "$WORK/local/$stem" -type f | wc -l)))
    n_slurm=$((n_slurm + $(find "$WORK/slurm-out/$stem" -type f 2>/dev/null | wc -l)))
    # timing.json: wall-clock times of the bake, the one product that is not reproducible.
    diff -rq -x timing.json "$WORK/local/$stem" "$WORK/slurm-out/$stem" >>"$WORK/diff.txt" 2>&1 || true
done
if [[ ! -s $WORK/diff.txt ]]; then
    echo "   identical: $n_local files, $(du -shc "${STEMS[@]/#/$WORK/local/}" | tail -n 1 | cut -f1)"
else
    echo "   $n_local files local, $n_slurm from Slurm; differences:" >&2
    sed 's/^/   /' "$WORK/diff.txt" >&2
    # Name the differing values of JSON files (manifests), and where binary files first differ.
    grep '^Files .* differ$' "$WORK/diff.txt" | sed -E 's/^Files (.*) and (.*) differ$/\1\t\2/' |
        while IFS=$'\t' read -r left right; do
            if [[ $left == *.json ]] && command -v python3 >/dev/null; then
                python3 - "$left" "$right" <<'PY' >&2
import json, sys
def walk(a, b, path=""):
    if type(a) is not type(b):
        print(f"     {path or '/'}: {a!r} vs {b!r}"[:300])
    elif isinstance(a, dict):
        for k in sorted(set(a) | set(b)):
            walk(a.get(k), b.get(k), f"{path}/{k}")
    elif isinstance(a, list) and len(a) == len(b):
        for i, (x, y) in enumerate(zip(a, b)):
            walk(x, y, f"{path}/{i}")
    elif a != b:
        print(f"     {path or '/'}: {a!r} vs {b!r}"[:300])
left, right = (json.load(open(p)) for p in sys.argv[1:3])
print(f"   {sys.argv[1]} (local) vs Slurm:")
walk(left, right)
PY
            else
                echo "   $(cmp "$left" "$right" 2>&1 | head -n 1)" >&2
            fi
        done
    die "the Slurm bake differs from the local bake"
fi
say "check_slurm: OK ($SHARDS shards, $(job_records "$array" --array | grep -c .) array tasks + merge, identical to the local bake)"
