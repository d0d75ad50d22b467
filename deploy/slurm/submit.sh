#!/usr/bin/env bash
# Submits a sharded bake to Slurm: a job array of N shards, then the merge, which runs only if
# every shard succeeded (--dependency=afterok). Prints the two job ids ("ARRAY_ID MERGE_ID").
#
#   deploy/slurm/submit.sh [-n N] [-d OUT_DIR] [-o STORE] [-s "SBATCH ARGS"] SCENE [BAKE ARGS...]
#
#   -n N         shards (array tasks) [default: 4]
#   -d OUT_DIR   where the shards and logs go, on storage every node sees [default: SCENE's
#                name with .shards]
#   -o STORE     the merged store [default: SCENE's name with .oslf, in the current directory]
#   -s ARGS      extra sbatch arguments for both jobs (partition, account, time, CPUs), e.g.
#                -s "--partition=cpu --cpus-per-task=16 --time=02:00:00"
#   BAKE ARGS    passed to every `oslf bake` (e.g. --preset thesis)
#
# OSLF names the oslf binary the jobs run [default: oslf on PATH, resolved here].
set -euo pipefail

here=$(cd "$(dirname "$0")" && pwd)
count=4 out_dir="" store="" extra=""
while getopts "n:d:o:s:h" opt; do
  case $opt in
    n) count=$OPTARG ;;
    d) out_dir=$OPTARG ;;
    o) store=$OPTARG ;;
    s) extra=$OPTARG ;;
    *) sed -n '2,17p' "$0" >&2; exit 2 ;;
  esac
done
shift $((OPTIND - 1))
if [ $# -lt 1 ]; then
  sed -n '2,17p' "$0" >&2
  exit 2
fi
scene=$1
shift
case $count in
  '' | *[!0-9]* | 0) echo "-n must be a positive number of shards, not '$count'" >&2; exit 2 ;;
esac
[ -f "$scene" ] || { echo "no scene file $scene" >&2; exit 2; }
name=$(basename "${scene%.*}")
out_dir=${out_dir:-$name.shards}
store=${store:-$name.oslf}
# The jobs may start in another directory: hand them absolute paths.
abs() { case $1 in /*) echo "$1" ;; *) echo "$PWD/$1" ;; esac; }
scene=$(abs "$scene") out_dir=$(abs "$out_dir") store=$(abs "$store")
oslf=${OSLF:-$(command -v oslf || true)}
[ -n "$oslf" ] && [ -x "$oslf" ] || { echo "no oslf binary: put it on PATH or set OSLF" >&2; exit 2; }
export OSLF=$(abs "$oslf")
mkdir -p "$out_dir"

# shellcheck disable=SC2086 # $extra holds several sbatch arguments
array_id=$(sbatch --parsable --export=ALL --array=0-$((count - 1)) $extra \
  --output="$out_dir/shard-%a.log" \
  "$here/bake-shard.sbatch" "$scene" "$out_dir" "$count" "$@")
array_id=${array_id%%;*} # --parsable prints "id" or "id;cluster"
# shellcheck disable=SC2086
merge_id=$(sbatch --parsable --export=ALL --dependency=afterok:"$array_id" --kill-on-invalid-dep=yes \
  $extra --output="$out_dir/merge.log" \
  "$here/merge.sbatch" "$out_dir" "$count" "$store")
merge_id=${merge_id%%;*}
echo "$array_id $merge_id"
