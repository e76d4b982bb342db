#!/usr/bin/env bash
# Runs a split render on the Kubernetes cluster of the current kubectl context:
#
#   deploy/k8s/run.sh N [render flags, e.g. --spp 4096 --seed 1]
#
# Before: the image `neumann:latest` (deploy/k8s/Dockerfile) where the nodes can pull it, the
# volume (kubectl apply -f deploy/k8s/volume.yaml), and the scene copied to /data/scene/scene.xml
# on it (README: "Renders bigger than one machine"). Applies render-job.yaml with N parts, waits
# for it to end (complete, or failed with the indexes that kept failing), then runs the merge.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
n=${1:?usage: run.sh N [render flags]}
shift
case "$n" in *[!0-9]* | 0) echo "error: N must be a positive number of parts" >&2; exit 2 ;; esac
args=${*:---spp 1024 --seed 0}
kubectl delete job neumann-render neumann-merge --ignore-not-found
sed -e "s/^  completions: .*/  completions: $n/" -e "s/^  parallelism: .*/  parallelism: $n/" \
    -e "s/^  maxFailedIndexes: .*/  maxFailedIndexes: $n/" \
    -e "/name: NEUMANN_PARTS/{n;s/value: .*/value: \"$n\"/}" \
    -e "/name: NEUMANN_ARGS/{n;s/value: .*/value: \"$args\"/}" \
    "$here/render-job.yaml" | kubectl apply -f -
# Ends when the job completes or fails (a failed index is retried backoffLimitPerIndex times first).
kubectl wait job/neumann-render --for=condition=Complete --timeout=-1s &
complete=$!
kubectl wait job/neumann-render --for=condition=Failed --timeout=-1s &
failed=$!
wait -n "$complete" "$failed" || true
kill "$complete" "$failed" 2>/dev/null || true
kubectl get job neumann-render -o jsonpath='{.status.failedIndexes}{"\n"}' | sed 's/^./failed parts (0-based indexes): &/;/^$/d'
kubectl apply -f "$here/merge-job.yaml"
kubectl wait job/neumann-merge --for=condition=Complete --timeout=600s || true
kubectl logs job/neumann-merge
