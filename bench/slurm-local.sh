#!/usr/bin/env bash
# A single-node Slurm on this machine, to run the farm recipes of examples/farm/ for real:
# installs slurm-wlm and munge with apt-get (as root), writes a one-node slurm.conf, starts
# munged, slurmctld and slurmd, builds kardia, submits examples/farm/slurm-submit.sh for a
# scene (a tiled frame joined by a dependent assemble step, and the frames as an array), waits
# for the jobs, checks the joined frame against a single render byte for byte, prints the
# queue's accounting; then kills a band mid-way (scancel of one array task), checks that the
# join still runs (afterany), fails naming that band and prints the line that re-runs it,
# runs that line, and checks the recovered frame byte for byte too; and stops the daemons it
# started.
#
#   bench/slurm-local.sh [SCENE] [TILES] [OUTDIR]
#
# Defaults: scenes/heartbeat.scene, 4 tiles, a fresh temporary directory. KARDIA: the binary
# (default: a release build).
set -euo pipefail
cd "$(dirname "$0")/.."
repo=$PWD
scene=${1:-scenes/heartbeat.scene}
tiles=${2:-4}
out=${3:-$(mktemp -d)}
out=$(cd "$out" && pwd)

if ! command -v slurmctld >/dev/null 2>&1 || ! command -v munged >/dev/null 2>&1; then
  apt-get update -qq
  DEBIAN_FRONTEND=noninteractive apt-get install -y -qq slurm-wlm munge >/dev/null
fi

if [[ -z "${KARDIA:-}" ]]; then
  cargo build --release --quiet
  KARDIA=$repo/target/release/kardia
fi
export KARDIA

host=$(hostname -s)
cpus=$(nproc)
conf_dir=/etc/slurm
mkdir -p "$conf_dir" /var/spool/slurmctld /var/spool/slurmd /var/log/slurm /run/munge
cat > "$conf_dir/slurm.conf" <<CONF
ClusterName=kardia-local
SlurmctldHost=$host
AuthType=auth/munge
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
ReturnToService=2
SlurmctldPidFile=/run/slurmctld.pid
SlurmdPidFile=/run/slurmd.pid
SlurmdSpoolDir=/var/spool/slurmd
StateSaveLocation=/var/spool/slurmctld
SlurmctldLogFile=/var/log/slurm/slurmctld.log
SlurmdLogFile=/var/log/slurm/slurmd.log
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
JobAcctGatherType=jobacct_gather/none
MpiDefault=none
NodeName=$host CPUs=$cpus State=UNKNOWN
PartitionName=render Nodes=$host Default=YES MaxTime=INFINITE State=UP
CONF

if [ ! -s /etc/munge/munge.key ]; then
  mkdir -p /etc/munge
  dd if=/dev/urandom of=/etc/munge/munge.key bs=1024 count=1 status=none
fi
chown -R munge:munge /etc/munge /run/munge 2>/dev/null || true
chmod 400 /etc/munge/munge.key
started=()
if ! pgrep -x munged >/dev/null; then
  runuser -u munge -- munged --force
  started+=(munged)
fi
if ! pgrep -x slurmctld >/dev/null; then
  slurmctld
  started+=(slurmctld)
fi
if ! pgrep -x slurmd >/dev/null; then
  slurmd
  started+=(slurmd)
fi
stop() {
  for daemon in "${started[@]}"; do
    pid=$(pgrep -x "$daemon" || true)
    [ -n "$pid" ] && kill "$pid" 2>/dev/null || true
  done
}
trap stop EXIT

for _ in $(seq 1 30); do
  if sinfo -h -o '%T' 2>/dev/null | grep -qE 'idle|mixed|alloc'; then break; fi
  sleep 1
done
echo "== sinfo"
sinfo

echo "== submit"
export KARDIA_ARGS="--spp 4"
examples/farm/slurm-submit.sh "$repo/$scene" "$out" "$tiles" | tee "$out/submitted.txt"

echo "== wait"
for _ in $(seq 1 600); do
  if [ -z "$(squeue -h -u "$(id -un)")" ]; then break; fi
  sleep 1
done
echo "== jobs (scontrol: every array task, the dependent assemble step)"
scontrol -o show job | tr ' ' '\n' |
  awk -F= '$1 == "JobId" { id = $2 } $1 == "ArrayTaskId" { id = id "_" $2 }
           $1 == "JobName" { name = $2 } $1 == "JobState" { state = $2 }
           $1 == "Dependency" { dep = $2 }
           $1 == "ExitCode" { printf "%-8s %-18s %-10s exit %-5s dependency %s\n", id, name, state, $2, dep }'

echo "== results in $out"
echo "parts: $(ls "$out"/part_*.png | wc -l), logs: $(ls "$out"/*.log | wc -l)"
"$KARDIA" render "$repo/$scene" --spp 4 --quiet -o "$out/single_render.png"
if cmp "$out/frame_0000_tiled.png" "$out/single_render.png"; then
  echo "joined tiles == single render (byte for byte)"
else
  echo "joined tiles differ from the single render" >&2
  exit 1
fi
frames=$(ls "$out"/frame_[0-9][0-9][0-9][0-9].png | wc -l)
echo "frames rendered by the array: $frames"

echo "== a band killed mid-way, and the recovery the join prints"
killed=$out/killed
mkdir -p "$killed"
export KARDIA_ARGS="--spp 64"
export SCENE=$repo/$scene OUT=$killed TILES=$tiles IMAGE=frame_0000_tiled.png RECIPES=$repo/examples/farm
tiles_job=$(sbatch --parsable --chdir="$killed" --array=0-$((tiles - 1)) --export=ALL examples/farm/slurm-tiles.sbatch)
join_job=$(sbatch --parsable --chdir="$killed" --dependency=afterany:"$tiles_job" --export=ALL examples/farm/slurm-assemble.sbatch)
echo "tiles array: $tiles_job  assemble (afterany): $join_job"
victim=${tiles_job}_1
for _ in $(seq 1 120); do
  [ "$(squeue -h -j "$victim" -o %T 2>/dev/null)" = RUNNING ] && break
  sleep 0.5
done
sleep 1
scancel "$victim"
echo "scancel $victim (band 1, running)"
for _ in $(seq 1 600); do
  if [ -z "$(squeue -h -u "$(id -un)")" ]; then break; fi
  sleep 1
done
if [ -n "$(squeue -h -u "$(id -un)")" ]; then
  echo "jobs still queued after the killed band:" >&2
  squeue >&2
  exit 1
fi
echo "join job $join_job: $(scontrol -o show job "$join_job" | grep -oE 'JobState=[A-Z]+|ExitCode=[0-9:]+' | tr '\n' ' ')"
echo "its log:"
sed 's/^/  /' "$killed/kardia-assemble.log"
leftovers=$(find "$killed" -name '.*.tmp' | wc -l)
echo "temporary files left by the killed band: $leftovers"
recovery=$(grep -A1 '^Re-run them and this join with:' "$killed/kardia-assemble.log" | tail -1)
[ -n "$recovery" ] || { echo "the join printed no recovery line" >&2; exit 1; }
rm "$killed/kardia-assemble.log"
echo "== recovery: the printed line"
eval "$recovery"
for _ in $(seq 1 600); do
  if [ -z "$(squeue -h -u "$(id -un)")" ]; then break; fi
  sleep 1
done
"$KARDIA" render "$repo/$scene" --spp 64 --quiet -o "$killed/single_render.png"
if cmp "$killed/frame_0000_tiled.png" "$killed/single_render.png"; then
  echo "recovered: joined tiles == single render (byte for byte)"
else
  echo "the recovered frame differs from the single render" >&2
  exit 1
fi
