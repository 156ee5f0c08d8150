#!/usr/bin/env bash
# A split render on a real Slurm: installs Debian's slurm-wlm and munge when missing,
# starts a one-node cluster on this machine, submits a 4-task job array rendering a
# suite scene (`ember render --task-from-env`) and a merge job that depends on it,
# waits, and checks the merged image against a single-process render byte for byte.
#
#   scripts/test-slurm.sh [SCENE] [ESTIMATOR] [SPP]
#   (defaults: ../shared/scenes/cornell-box/scene.xml, spcbpt, 12)
#
# Needs root (package install, munge key, slurmd). Everything else lives under a
# temporary folder, removed at the end with the daemons stopped. docs/distributed.md
# records a run.
set -euo pipefail
cd "$(dirname "$0")/.."
ROOT=$PWD
SCENE=${1:-$ROOT/../shared/scenes/cornell-box/scene.xml}
ESTIMATOR=${2:-spcbpt}
SPP=${3:-12}
TASKS=4
RES=(--width 96 --height 96)

if [ "$(id -u)" != 0 ]; then
    echo "test-slurm: needs root (installs packages, starts slurmd)" >&2
    exit 2
fi
if ! command -v slurmctld >/dev/null || ! command -v munged >/dev/null; then
    echo "test-slurm: installing slurm-wlm and munge"
    apt-get update -qq
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq slurm-wlm munge >/dev/null
fi

cargo build --release -q -p ember-cli
EMBER=$ROOT/target/release/ember

WORK=$(mktemp -d /tmp/ember-slurm.XXXXXX)
cleanup() {
    [ -f "$WORK/slurmd.pid" ] && kill "$(cat "$WORK/slurmd.pid")" 2>/dev/null || true
    [ -f "$WORK/slurmctld.pid" ] && kill "$(cat "$WORK/slurmctld.pid")" 2>/dev/null || true
    [ -f "$WORK/munged.pid" ] && kill "$(cat "$WORK/munged.pid")" 2>/dev/null || true
    sleep 1
    rm -rf "$WORK"
}
trap cleanup EXIT

# munge: a key of our own, its socket and pid under $WORK.
mkdir -p "$WORK/munge" "$WORK/spool" "$WORK/state" "$WORK/parts"
dd if=/dev/urandom of="$WORK/munge/munge.key" bs=1024 count=1 status=none
chmod 700 "$WORK/munge"
chmod 400 "$WORK/munge/munge.key"
munged --key-file="$WORK/munge/munge.key" --socket="$WORK/munge/socket" \
    --pid-file="$WORK/munged.pid" --log-file="$WORK/munge/log" --seed-file="$WORK/munge/seed" --force

HOST=$(hostname -s)
CPUS=$(nproc)
cat >"$WORK/slurm.conf" <<EOF
ClusterName=ember-test
SlurmctldHost=$HOST
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
AuthInfo=socket=$WORK/munge/socket
CredType=cred/munge
SlurmctldPort=46817
SlurmdPort=46818
StateSaveLocation=$WORK/state
SlurmdSpoolDir=$WORK/spool
SlurmctldPidFile=$WORK/slurmctld.pid
SlurmdPidFile=$WORK/slurmd.pid
SlurmctldLogFile=$WORK/slurmctld.log
SlurmdLogFile=$WORK/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SwitchType=switch/none
MpiDefault=none
ReturnToService=2
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
JobCompType=jobcomp/none
JobAcctGatherType=jobacct_gather/none
NodeName=$HOST CPUs=$CPUS State=UNKNOWN
PartitionName=debug Nodes=$HOST Default=YES MaxTime=INFINITE State=UP
EOF
export SLURM_CONF=$WORK/slurm.conf
slurmctld -i
slurmd
for _ in $(seq 60); do
    sinfo -h -o %T 2>/dev/null | grep -qE '^idle' && break
    sleep 1
done
sinfo

# The job array: each task renders its share (--task-from-env reads SLURM_ARRAY_TASK_ID,
# _MIN and _COUNT) with one thread, and writes part-<index>.exr atomically.
cd "$WORK"
ARRAY=$(sbatch --parsable --array=0-$((TASKS - 1)) --cpus-per-task=1 --output="$WORK/task-%a.log" \
    --wrap "$EMBER render '$SCENE' -e $ESTIMATOR ${RES[*]} --spp $SPP --seed 7 --threads 1 --task-from-env -o '$WORK/parts/part-{task}.exr'")
MERGE=$(sbatch --parsable --dependency=afterok:$ARRAY --output="$WORK/merge.log" \
    --wrap "$EMBER merge $WORK/parts/part-*.exr -o $WORK/merged.exr")
echo "submitted array $ARRAY ($TASKS tasks) and merge $MERGE"
for _ in $(seq 600); do
    [ -z "$(squeue -h -j "$ARRAY,$MERGE" 2>/dev/null)" ] && break
    sleep 1
done
for i in $(seq 0 $((TASKS - 1))); do tail -n 1 "$WORK/task-$i.log"; done
cat "$WORK/merge.log"
test -f "$WORK/merged.exr" || { echo "test-slurm: FAILED: no merged image"; cat "$WORK/slurmctld.log" | tail -20; exit 1; }

"$EMBER" render "$SCENE" -e "$ESTIMATOR" "${RES[@]}" --spp "$SPP" --seed 7 --threads 2 -o "$WORK/single.exr" | tail -n 1
if cmp "$WORK/merged.exr" "$WORK/single.exr"; then
    echo "test-slurm: OK: the merge of $TASKS Slurm array tasks equals the single-process render byte for byte"
else
    echo "test-slurm: FAILED: merged and single-process images differ"
    exit 1
fi
