#!/usr/bin/env bash
# Validates the Kubernetes manifests offline against the API schemas (no cluster needed), strict
# (unknown fields are errors), with kubernetes-validate from PyPI in a virtual environment outside
# the repository; also the manifest run.sh generates for N = 3.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
venv=${KUBE_VALIDATE_VENV:-${TMPDIR:-/tmp}/neumann-kube-validate}
[ -x "$venv/bin/kubernetes-validate" ] || { python3 -m venv "$venv" && "$venv/bin/pip" install -q kubernetes-validate; }
version=${KUBERNETES_VERSION:-1.33.0}
"$venv/bin/kubernetes-validate" --strict -k "$version" "$here/volume.yaml" "$here/render-job.yaml" "$here/merge-job.yaml"
generated=$(mktemp --suffix=.yaml)
trap 'rm -f "$generated"' EXIT
# run.sh's edits, applied to a copy.
n=3 args="--spp 64"
sed -e "s/^  completions: .*/  completions: $n/" -e "s/^  parallelism: .*/  parallelism: $n/" \
    -e "s/^  maxFailedIndexes: .*/  maxFailedIndexes: $n/" \
    -e "/name: NEUMANN_PARTS/{n;s/value: .*/value: \"$n\"/}" \
    -e "/name: NEUMANN_ARGS/{n;s/value: .*/value: \"$args\"/}" \
    "$here/render-job.yaml" > "$generated"
grep -q 'completions: 3' "$generated" && grep -q 'value: "3"' "$generated" && grep -q 'value: "--spp 64"' "$generated"
"$venv/bin/kubernetes-validate" --strict -k "$version" "$generated"
echo "kubernetes manifests valid (Kubernetes $version schemas)"
