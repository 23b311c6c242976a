#!/usr/bin/env bash
# End-to-end farm test on a real single-node Slurm (Debian's slurmctld, slurmd,
# slurm-client, munge), run by .ci/run as root:
#   1. a demo animation cut into 3 segments as a job array (+ afterok assemble job) equals
#      the single-run render bit for bit;
#   2. an array task cancelled mid-way and resubmitted (its script has --resume) loses
#      nothing and the folder again equals the single run.
# Usage: scripts/ci/slurm.sh PATH/TO/chronolux. Starts and stops its own daemons; bounded
# in time (every wait has a deadline).
set -euo pipefail
BIN=$(readlink -f "$1")
WORK=$(mktemp -d /tmp/chronolux-slurm.XXXXXX)
log() { echo "slurm-test: $*"; }

if ! command -v slurmctld >/dev/null || ! command -v munged >/dev/null || ! command -v sbatch >/dev/null; then
    log "installing slurm and munge"
    apt-get update -qq
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends \
        slurmctld slurmd slurm-client munge >/dev/null
fi

HOST=$(hostname -s)
CPUS=$(nproc)
MEM=$(awk '/MemTotal/ {print int($2 / 1024 * 0.8)}' /proc/meminfo)
mkdir -p /etc/slurm /var/spool/slurmctld /var/spool/slurmd /var/log/slurm /run/munge /etc/munge
if [ ! -s /etc/munge/munge.key ]; then
    dd if=/dev/urandom bs=1 count=1024 of=/etc/munge/munge.key status=none
fi
chown -R munge:munge /etc/munge /run/munge /var/lib/munge /var/log/munge 2>/dev/null || true
chmod 400 /etc/munge/munge.key
chmod 755 /run/munge
cat > /etc/slurm/slurm.conf <<CONF
ClusterName=chronolux-ci
SlurmctldHost=$HOST
AuthType=auth/munge
CredType=cred/munge
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SlurmUser=root
SlurmdUser=root
StateSaveLocation=/var/spool/slurmctld
SlurmdSpoolDir=/var/spool/slurmd
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
ReturnToService=2
MpiDefault=none
SlurmctldPidFile=/run/slurmctld.pid
SlurmdPidFile=/run/slurmd.pid
SlurmctldLogFile=/var/log/slurm/slurmctld.log
SlurmdLogFile=/var/log/slurm/slurmd.log
JobCompType=jobcomp/none
AccountingStorageType=accounting_storage/none
SlurmctldTimeout=30
SlurmdTimeout=30
NodeName=$HOST CPUs=$CPUS RealMemory=$MEM State=UNKNOWN
PartitionName=ci Nodes=$HOST Default=YES MaxTime=INFINITE State=UP
CONF

stop() {
    scancel --user=root >/dev/null 2>&1 || true
    [ -f /run/slurmd.pid ] && kill "$(cat /run/slurmd.pid)" 2>/dev/null || true
    [ -f /run/slurmctld.pid ] && kill "$(cat /run/slurmctld.pid)" 2>/dev/null || true
    pkill -x munged 2>/dev/null || true
    sleep 1
}
fail() {
    log "FAILED: $*"
    tail -n 30 /var/log/slurm/slurmctld.log /var/log/slurm/slurmd.log 2>/dev/null || true
    for f in "$WORK"/*/logs/*.log; do [ -f "$f" ] && { echo "== $f"; tail -n 20 "$f"; }; done
    stop
    exit 1
}
trap 'fail "unexpected error on line $LINENO"' ERR

stop
runuser -u munge -- /usr/sbin/munged || /usr/sbin/munged --force
slurmctld -c
slurmd
# The node comes up idle within seconds.
for _ in $(seq 60); do
    state=$(sinfo -h -n "$HOST" -o %t 2>/dev/null || true)
    case "$state" in idle*|mix*|alloc*) break ;; down*|drain*) scontrol update nodename="$HOST" state=resume || true ;; esac
    sleep 1
done
[ "$(sinfo -h -n "$HOST" -o %t | tr -d '*')" = idle ] || fail "node not idle: $(sinfo)"
log "slurm up: $(sinfo -h -o '%P %D %t %C')"

# Waits until the queue is empty (at most $1 seconds).
drain() {
    for _ in $(seq "$1"); do
        [ -z "$(squeue -h)" ] && return 0
        sleep 1
    done
    fail "queue not empty after $1 s: $(squeue)"
}
# Every frame of $1 equals the same frame of $2.
same() {
    for f in "$2"/frame_*.exr; do
        cmp -s "$f" "$1/$(basename "$f")" || fail "$(basename "$f") of $1 differs from the single run"
    done
}

ARGS=(--method stbpt --window 1 --frames 0..6 --resolution 24x24 --spp 2 --no-preview)
"$BIN" render "${ARGS[@]}" --output "$WORK/single" 2>/dev/null

# 1. A job array of 3 segments and an afterok assemble job.
"$BIN" farm slurm "${ARGS[@]}" --segment-length 2 --max-parallel 2 --output "$WORK/farm" --submit | tee "$WORK/ids"
grep -q '^render job [0-9]' "$WORK/ids" || fail "no render job id printed"
grep -q '^assemble job [0-9]' "$WORK/ids" || fail "no assemble job id printed"
drain 300
same "$WORK/farm" "$WORK/single"
[ -f "$WORK/farm/run.json" ] || fail "the assemble job did not write run.json"
log "3 segments equal the single run; assembled"

# 2. Cancel a running array task mid-way, resubmit it with --resume.
ARGS2=(--method path --frames 0..6 --resolution 96x96 --spp 256 --no-preview)
"$BIN" render "${ARGS2[@]}" --output "$WORK/single2" 2>/dev/null
"$BIN" farm slurm "${ARGS2[@]}" --segment-length 2 --max-parallel 1 --output "$WORK/farm2" --submit | tee "$WORK/ids2"
JOB=$(awk '/^render job/ {print $3}' "$WORK/ids2")
ASM=$(awk '/^assemble job/ {print $3}' "$WORK/ids2")
task=""
for _ in $(seq 120); do
    task=$(squeue -h -j "$JOB" -t RUNNING -o %K | head -n 1)
    [ -n "$task" ] && break
    sleep 0.5
done
[ -n "$task" ] || fail "no array task of $JOB ran"
sleep 1
scancel "${JOB}_${task}"
log "cancelled array task ${JOB}_${task}"
# The assemble job can no longer run (afterok); it is cancelled, the others finish.
for _ in $(seq 300); do
    [ -z "$(squeue -h -j "$JOB")" ] && break
    sleep 1
done
scancel "$ASM" 2>/dev/null || true
drain 60
[ -f "$WORK/farm2/run.json" ] && fail "assemble ran although a segment was cancelled"
sbatch --array="$task" "$WORK/farm2/render.sbatch" >/dev/null
drain 300
"$BIN" assemble "$WORK/farm2" --no-preview
same "$WORK/farm2" "$WORK/single2"
ls "$WORK/farm2" | grep -q '\.tmp$' && fail "a temporary file was left behind"
log "cancelled task resubmitted with --resume: frames equal the single run"

trap - ERR
stop
rm -rf "$WORK"
log "passed"
