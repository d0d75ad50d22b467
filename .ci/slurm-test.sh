#!/usr/bin/env bash
# Runs deploy/slurm for real on a one-node Slurm cluster started here: installs slurm-wlm and
# munge (apt-get, as root, e.g. in a fresh Debian container), starts munged, slurmctld and
# slurmd on this host (no systemd, no cgroups), submits a 4-shard bake of a small scene plus
# the merge with deploy/slurm/submit.sh, waits for them, and compares the merged store byte
# for byte with a local bake. Every daemon it started is stopped on exit, pass or fail.
#
#   .ci/slurm-test.sh            (from anywhere; uses $CARGO_TARGET_DIR or target/release/oslf,
#                                 building it if needed)
#
# SLURM_TEST_TIMEOUT: seconds to wait for the jobs [default: 600].
set -euo pipefail
cd "$(dirname "$0")/.."
repo=$PWD

if [ "$(id -u)" -ne 0 ]; then
  echo "slurm-test.sh runs the Slurm daemons as root: run it as root (in a container)" >&2
  exit 1
fi
export DEBIAN_FRONTEND=noninteractive
if ! command -v slurmctld >/dev/null || ! command -v slurmd >/dev/null || ! command -v munged >/dev/null; then
  apt-get update -qq
  apt-get install -y -qq --no-install-recommends slurm-wlm munge >/dev/null
fi
# The binary `cargo test --workspace --release --ignore-rust-version` built (CARGO_TARGET_DIR respected).
target_dir=${CARGO_TARGET_DIR:-$repo/target}
case $target_dir in /*) ;; *) target_dir=$repo/$target_dir ;; esac
oslf=$target_dir/release/oslf
[ -x "$oslf" ] || (cd "$repo" && cargo build --release --bin oslf)

work=$(mktemp -d /tmp/oslf-slurm-test.XXXXXX)
pids=()
array_id="" merge_id=""
host=$(hostname)
export SLURM_CONF=$work/slurm.conf

stop_all() {
  local rc=$?
  set +e
  if [ "$rc" -ne 0 ] && [ -n "$array_id$merge_id" ] && [ -n "${slurmctld_pid:-}" ]; then
    # shellcheck disable=SC2086 # either may be empty
    scancel $array_id $merge_id 2>/dev/null
  fi
  # Daemons in reverse start order: slurmd, slurmctld, munged.
  for ((i = ${#pids[@]} - 1; i >= 0; i--)); do
    kill "${pids[i]}" 2>/dev/null
  done
  for pid in "${pids[@]}"; do
    for _ in $(seq 50); do
      kill -0 "$pid" 2>/dev/null || break
      sleep 0.1
    done
    kill -9 "$pid" 2>/dev/null
    wait "$pid" 2>/dev/null
  done
  if [ "$rc" -eq 0 ]; then
    rm -rf "$work"
  else
    echo "slurm test FAILED (exit $rc); its files are in $work" >&2
  fi
  exit "$rc"
}
trap stop_all EXIT

dump() {
  set +e
  echo "---- squeue" >&2
  squeue --all >&2
  for id in $array_id $merge_id; do
    echo "---- scontrol show job $id" >&2
    scontrol show job "$id" >&2
  done
  for f in "$work"/shards/*.log "$work"/*.log "$work"/*.out; do
    [ -f "$f" ] || continue
    echo "---- $f (last 40 lines)" >&2
    tail -n 40 "$f" >&2
  done
}

# munge: a fresh key, a socket of our own.
mkdir -p "$work/munge" "$work/state" "$work/spool" "$work/shards"
chmod 700 "$work/munge"
dd if=/dev/urandom of="$work/munge/munge.key" bs=1024 count=1 status=none
chmod 400 "$work/munge/munge.key"
munged --foreground --force --key-file="$work/munge/munge.key" \
  --socket="$work/munge/munge.socket" --pid-file="$work/munge/munged.pid" \
  --seed-file="$work/munge/munged.seed" --log-file="$work/munged.log" >>"$work/munged.out" 2>&1 &
pids+=($!)
for _ in $(seq 100); do
  [ -S "$work/munge/munge.socket" ] && break
  sleep 0.1
done
[ -S "$work/munge/munge.socket" ] || { echo "munged did not start" >&2; dump; exit 1; }

cpus=$(nproc)
# Small enough for any machine this runs on (slurmd drains a node with less than declared).
mem=$(awk '/MemTotal/ { m = int($2 / 1024 / 2); print (m > 1024 ? 1024 : m) }' /proc/meminfo)
cat >"$SLURM_CONF" <<EOF
ClusterName=oslfci
SlurmctldHost=$host(127.0.0.1)
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
AuthInfo=socket=$work/munge/munge.socket
CredType=cred/munge
SlurmctldPort=16817
SlurmdPort=16818
MpiDefault=none
ProctrackType=proctrack/pgid
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
ReturnToService=2
MinJobAge=3600
StateSaveLocation=$work/state
SlurmdSpoolDir=$work/spool
SlurmctldPidFile=$work/slurmctld.pid
SlurmdPidFile=$work/slurmd.pid
SlurmctldLogFile=$work/slurmctld.log
SlurmdLogFile=$work/slurmd.log
NodeName=$host NodeAddr=127.0.0.1 CPUs=$cpus RealMemory=$mem State=UNKNOWN
PartitionName=ci Nodes=$host Default=YES MaxTime=INFINITE State=UP
EOF

# In the foreground (-D) as our children, so the trap knows their PIDs; output to the logs.
slurmctld -D -i -f "$SLURM_CONF" >>"$work/slurmctld.out" 2>&1 &
slurmctld_pid=$!
pids+=("$slurmctld_pid")
slurmd -D -f "$SLURM_CONF" -N "$host" >>"$work/slurmd.out" 2>&1 &
pids+=($!)

echo "waiting for node $host to be idle"
idle=""
for _ in $(seq 120); do
  state=$(sinfo -h -n "$host" -o '%t' 2>/dev/null || true)
  if [ "$state" = idle ]; then
    idle=1
    break
  fi
  sleep 0.5
done
[ -n "$idle" ] || { echo "the node never became idle (state: ${state:-none})" >&2; sinfo -N -l >&2 || true; dump; exit 1; }
sinfo

# The small scene of tests/cli_shard.rs: 24 sample points and an environment cube.
cat >"$work/lid.toml" <<'EOF'
[camera]
position = [6.0, -6.0, 4.0]
target = [0.0, 0.0, 1.0]

[environment.sky]
sun_direction = [0.6, -0.4, 0.7]
sun_irradiance = [5.0, 5.0, 5.0]

[[object]]
patches = "newell-teapot"
select = [20, 28]
material = { color = [0.1, 0.4, 0.1] }

[bake]
sample_count = 12
cube_resolution = 2
sample_map_resolution = 4
samples_per_texel = 1
env_cube = true
EOF

cd "$work"
ids=$(OSLF=$oslf "$repo/deploy/slurm/submit.sh" -n 4 \
  -d "$work/shards" -o "$work/merged.oslf" -s "--cpus-per-task=1" "$work/lid.toml")
read -r array_id merge_id <<<"$ids"
echo "submitted array job $array_id and merge job $merge_id"

# Meanwhile the reference: a local bake of the same scene.
"$oslf" bake "$work/lid.toml" -o "$work/local.oslf" --quiet --preview none >/dev/null

timeout=${SLURM_TEST_TIMEOUT:-600}
start=$SECONDS
while [ -n "$(squeue -h -j "$array_id,$merge_id" -o '%i' 2>/dev/null)" ]; do
  if ((SECONDS - start > timeout)); then
    echo "the jobs did not finish within $timeout s" >&2
    dump
    exit 1
  fi
  sleep 1
done
merge_state=$(scontrol show job "$merge_id" 2>/dev/null | sed -n 's/.*JobState=\([A-Z_]*\).*/\1/p' | head -n 1)
if [ "$merge_state" != COMPLETED ] || [ ! -f "$work/merged.oslf" ]; then
  echo "the merge job ended ${merge_state:-in an unknown state}, without a complete store" >&2
  dump
  exit 1
fi
cat "$work/shards/merge.log"
if ! cmp "$work/merged.oslf" "$work/local.oslf"; then
  echo "the store merged from the Slurm shards differs from the local bake" >&2
  dump
  exit 1
fi
echo "slurm test passed: 4 shards + merge on Slurm equal the local bake byte for byte ($((SECONDS - start)) s of jobs)"
