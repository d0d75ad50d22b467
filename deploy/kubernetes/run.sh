#!/usr/bin/env bash
# Runs a sharded bake on Kubernetes: the shared volume, the scene as a ConfigMap, the Indexed
# bake Job, then (once every shard completed) the merge Job.
#
#   deploy/kubernetes/run.sh SCENE [NAMESPACE]
#
# Edit N (completions, parallelism, SHARDS) in bake-job.yaml and merge-job.yaml first; the
# image oslf:latest must hold the oslf binary (README.md). Fetch the store afterwards from the
# volume, e.g. with a pod that mounts it and `kubectl cp`.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
scene=${1:?usage: $0 SCENE [NAMESPACE]}
ns=(--namespace "${2:-default}")

kubectl "${ns[@]}" apply -f "$here/pvc.yaml"
kubectl "${ns[@]}" create configmap oslf-scene --from-file=scene.toml="$scene" \
  --dry-run=client -o yaml | kubectl "${ns[@]}" apply -f -
kubectl "${ns[@]}" delete job oslf-bake oslf-merge --ignore-not-found
kubectl "${ns[@]}" apply -f "$here/bake-job.yaml"
# Fails (and skips the merge) if the Job fails or does not finish within a day.
kubectl "${ns[@]}" wait --for=condition=complete --timeout=24h job/oslf-bake
kubectl "${ns[@]}" apply -f "$here/merge-job.yaml"
kubectl "${ns[@]}" wait --for=condition=complete --timeout=2h job/oslf-merge
kubectl "${ns[@]}" logs job/oslf-merge
