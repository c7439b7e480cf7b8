#!/usr/bin/env bash
# deploy/slurm on a real Slurm, end to end, on this machine alone:
#   1. installs what Debian 12's slurm-wlm consists of (slurmctld, slurmd, slurm-client, without
#      the recommended plugins) and munge if they are missing (apt-get; needs root),
#   2. starts munged, slurmctld and slurmd by hand (no systemd, no cgroups: proctrack/linuxproc)
#      with a slurm.conf for one node, this host, with its real CPUs and memory, on ports of its own,
#   3. submits the part array with submit.sh (PARTS parts of cornell_box, 64x64, path, CPU),
#   4. stops task 1 mid-render with `scancel --signal=TERM --batch`, checks that it kept its
#      samples (exit 143, part_1.exr with 1 <= spp < SPP) and that the merge is held back,
#   5. resumes it with resume.sh, which also queues the merge again, and waits for the merge,
#   6. checks part_1 reached SPP, the merged image has PARTS x SPP spp and seeds 1..PARTS, and
#      that it is pixel for pixel the merge of an uninterrupted render of seed 1 with the other
#      parts (hexray compare: RMSE 0),
#   7. stops the daemons and removes its folder (KEEP=1 keeps it), and prints its wall-clock time.
# Usage: deploy/slurm/test-real-slurm.sh   (after cargo build --release; HEXRAY names another binary)
# Environment: PARTS (4), SPP (1500), PORT (16817; slurmd takes PORT+1), KEEP.
set -euo pipefail
start=$(date +%s.%N)
repo=$(cd "$(dirname "$0")/../.." && pwd)
HEXRAY=$(realpath -m "${HEXRAY:-$repo/target/release/hexray}")
PARTS=${PARTS:-4} SPP=${SPP:-1500} PORT=${PORT:-16817}
say() { printf 'test-real-slurm: %s\n' "$*" >&2; }
fail() { say "FAIL: $*"; exit 1; }
elapsed() { awk -v a="$start" -v b="$(date +%s.%N)" 'BEGIN { printf "%.1f", b - a }'; }

[ -x "$HEXRAY" ] || fail "no $HEXRAY: run cargo build --release first"
if [ "$(id -u)" -ne 0 ]; then
    # slurmd must run as root to start jobs.
    exec sudo -E HEXRAY="$HEXRAY" "$0" "$@"
fi

# 1. Packages.
if ! command -v slurmctld >/dev/null || ! command -v slurmd >/dev/null \
    || ! command -v sbatch >/dev/null || ! command -v munged >/dev/null; then
    say "installing slurm-wlm and munge"
    export DEBIAN_FRONTEND=noninteractive
    pkgs=(slurmctld slurmd slurm-client munge)
    apt-get install -y -qq --no-install-recommends "${pkgs[@]}" >/dev/null 2>&1 || {
        apt-get update -qq
        apt-get install -y -qq --no-install-recommends "${pkgs[@]}" >/dev/null
    }
    say "installed in $(elapsed) s"
fi

W=$(mktemp -d /tmp/hexray-slurm.XXXXXX)
chmod 755 "$W"
mkdir -p "$W/state" "$W/spool" "$W/parts" "$W/ref"
started_munged=""
cleanup() {
    rc=$?
    set +e
    if [ -n "${SLURM_CONF:-}" ] && [ -f "$W/slurmctld.pid" ]; then
        scancel --user=root >/dev/null 2>&1
    fi
    for d in slurmd slurmctld; do
        if [ -f "$W/$d.pid" ]; then
            pid=$(cat "$W/$d.pid")
            kill "$pid" 2>/dev/null
            for _ in $(seq 50); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
        fi
    done
    if [ -n "$started_munged" ]; then
        kill "$(cat /run/munge/munged.pid)" 2>/dev/null
    fi
    if [ "$rc" -ne 0 ]; then
        for f in "$W"/slurmctld.log "$W"/slurmd.log "$W"/parts/slurm-*.out; do
            [ -s "$f" ] && { echo "---- $f (last lines)"; tail -n 25 "$f"; } >&2
        done
    fi
    if [ -n "${KEEP:-}" ]; then say "kept $W"; else rm -rf "$W"; fi
    say "$([ "$rc" -eq 0 ] && echo PASS || echo FAIL) in $(elapsed) s (wall clock, packages included)"
    exit "$rc"
}
trap cleanup EXIT

# 2. munged (default socket, the key the package made) and Slurm's daemons.
if ! munge -n 2>/dev/null | unmunge >/dev/null 2>&1; then
    [ -s /etc/munge/munge.key ] || {
        dd if=/dev/urandom of=/etc/munge/munge.key bs=1024 count=1 2>/dev/null
        chown munge:munge /etc/munge/munge.key
        chmod 400 /etc/munge/munge.key
    }
    mkdir -p /run/munge
    chown munge:munge /run/munge
    chmod 755 /run/munge
    runuser -u munge -- munged
    started_munged=1
    munge -n | unmunge >/dev/null || fail "munged does not answer"
fi

host=$(hostname -s)
node=$(slurmd -C | sed -n 1p) # NodeName=HOST CPUs=.. Boards=.. ... RealMemory=..
cat >"$W/slurm.conf" <<EOF
ClusterName=hexray-test
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=$PORT
SlurmdPort=$((PORT + 1))
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
SchedulerType=sched/backfill
MpiDefault=none
SwitchType=switch/none
ReturnToService=2
StateSaveLocation=$W/state
SlurmdSpoolDir=$W/spool
SlurmctldPidFile=$W/slurmctld.pid
SlurmdPidFile=$W/slurmd.pid
SlurmctldLogFile=$W/slurmctld.log
SlurmdLogFile=$W/slurmd.log
$node NodeAddr=127.0.0.1 State=UNKNOWN
PartitionName=test Nodes=$host Default=YES MaxTime=INFINITE State=UP
EOF
export SLURM_CONF=$W/slurm.conf
slurmctld -i -f "$SLURM_CONF"
slurmd -f "$SLURM_CONF"
for _ in $(seq 100); do
    [ "$(sinfo -h -o %T 2>/dev/null)" = idle ] && break
    sleep 0.2
done
[ "$(sinfo -h -o %T)" = idle ] || fail "the node is not idle: $(sinfo -h -o '%T %E')"
say "Slurm $(sinfo -V | cut -d' ' -f2) up: $node ($(elapsed) s)"

job_field() { scontrol show job "$1" | tr ' ' '\n' | sed -n "s/^$2=//p" | sed -n 1p; }
queued() { [ -n "$(squeue -h -j "$1" 2>/dev/null)" ]; }
wait_gone() { # JOB SECONDS: until no task of JOB is pending or running
    local t=0
    while queued "$1"; do
        sleep 0.2
        t=$((t + 1))
        [ "$t" -lt $(($2 * 5)) ] || fail "job $1 still queued after $2 s: $(squeue -j "$1")"
    done
}
spp_of() { LC_ALL=C grep -a -o -m 1 '^spp=[0-9]*' "$1" | head -n 1 | cut -d= -f2; }
seeds_of() { LC_ALL=C grep -a -o -m 1 '^seeds=[0-9,]*' "$1" | head -n 1 | cut -d= -f2; }

# 3. The array and the merge, as a user submits them (paths from this folder).
cd "$W"
export SCENE=$repo/scenes/cornell_box.json SPP OUTDIR=$W/parts HEXRAY
export EXTRA_ARGS="--backend cpu --method path --width 64 --height 64" RESUME_ARGS="--backend cpu"
read -r array merge < <("$repo/deploy/slurm/submit.sh" --array=1-"$PARTS" --cpus-per-task=1)
say "submitted array $array and merge $merge"

# 4. Stop task 1 while it renders.
t=0
until [ "$(squeue -h -j "${array}_1" -o %T 2>/dev/null)" = RUNNING ]; do
    sleep 0.1
    t=$((t + 1))
    [ "$t" -lt 300 ] || fail "task 1 did not start: $(squeue)"
done
sleep 0.7 # some hundred samples in, several seconds from the end
queued "${array}_1" || fail "task 1 ended before it could be stopped; raise SPP"
# Once only: a second SIGTERM makes hexray exit at once.
scancel --signal=TERM --batch "${array}_1" || say "scancel exited $? (seen with Slurm 22.05 while delivering the signal)"
say "sent SIGTERM to task ${array}_1 ($(elapsed) s)"
wait_gone "$array" 120
state=$(job_field "${array}_1" JobState) code=$(job_field "${array}_1" ExitCode)
[ "$code" = "143:0" ] || fail "task 1: $state, exit $code; want hexray's 143 (128 + SIGTERM)"
[ -s parts/part_1.exr ] && [ -s parts/part_1.film ] || fail "task 1 wrote no part_1.exr/.film"
kept=$(spp_of parts/part_1.exr)
[ "$kept" -ge 1 ] && [ "$kept" -lt "$SPP" ] || fail "task 1 kept $kept spp; want 1..$((SPP - 1))"
for k in $(seq 2 "$PARTS"); do
    [ "$(job_field "${array}_$k" ExitCode)" = "0:0" ] || fail "task $k: $(job_field "${array}_$k" JobState)"
    [ "$(spp_of "parts/part_$k.exr")" = "$SPP" ] || fail "part_$k.exr has $(spp_of "parts/part_$k.exr") spp"
done
reason=$(job_field "$merge" Reason)
# Dependency, then DependencyNeverSatisfied once slurmctld has looked again.
[ "$(job_field "$merge" JobState)" = PENDING ] && case "$reason" in Dependency*) true ;; *) false ;; esac \
    || fail "merge $merge: $(job_field "$merge" JobState) ($reason); want it held back"
[ ! -e parts/merged.exr ] || fail "merged.exr written with a part missing"
say "task 1: $state, exit $code, kept $kept of $SPP spp; tasks 2-$PARTS done; merge held: $reason ($(elapsed) s)"

# 5. Resume task 1 and merge.
read -r array2 merge2 < <("$repo/deploy/slurm/resume.sh" "$array" "$merge" 1 --cpus-per-task=1)
say "resubmitted task 1 as $array2, merge as $merge2"
wait_gone "$merge2" 180
[ "$(job_field "${array2}_1" ExitCode)" = "0:0" ] || fail "resumed task: $(job_field "${array2}_1" JobState)"
[ "$(job_field "$merge2" JobState)" = COMPLETED ] || fail "merge $merge2: $(job_field "$merge2" JobState)"
say "resumed and merged ($(elapsed) s)"

# 6. The right image.
[ "$(spp_of parts/part_1.exr)" = "$SPP" ] || fail "resumed part_1.exr has $(spp_of parts/part_1.exr) spp"
total=$(spp_of parts/merged.exr)
[ "$total" = $((PARTS * SPP)) ] || fail "merged.exr has $total spp; want $((PARTS * SPP))"
[ "$(seeds_of parts/merged.exr)" = "$(seq -s, 1 "$PARTS")" ] || fail "merged seeds $(seeds_of parts/merged.exr)"
# The same image from an uninterrupted seed 1, rendered here without Slurm.
# shellcheck disable=SC2086
"$HEXRAY" render "$SCENE" --seed 1 --spp "$SPP" --threads "$(nproc)" --variance --quiet \
    --out ref/part_1.exr $EXTRA_ARGS
others=()
for k in $(seq 2 "$PARTS"); do others+=("parts/part_$k.exr"); done
"$HEXRAY" merge --quiet ref/part_1.exr "${others[@]}" -o ref/merged.exr
for pair in "part_1 ref/part_1.exr" "merged ref/merged.exr"; do
    set -- $pair
    rmse=$("$HEXRAY" compare --json "parts/$1.exr" "$2" | grep -o '"rmse":[^,]*' | cut -d: -f2)
    awk -v r="$rmse" 'BEGIN { exit !(r != "" && r + 0 == 0) }' || fail "parts/$1.exr differs from an uninterrupted render's: RMSE $rmse"
done
say "part_1 resumed to $SPP spp and merged.exr ($total spp, seeds $(seeds_of parts/merged.exr)) equal uninterrupted renders pixel for pixel"
