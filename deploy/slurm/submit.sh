#!/usr/bin/env bash
# Renders SCENE split into N parts on Slurm: an array job of N tasks (render.sbatch, one part
# each) and a merge job that runs when they have all ended (merge.sbatch). Prints the two job ids.
#
#   deploy/slurm/submit.sh SCENE N OUTPUT.exr [render flags…]
#
# PARTS_DIR (default: OUTPUT's folder/OUTPUT-parts) must be on a file system every node sees;
# NEUMANN names the binary (default: neumann on PATH). sbatch options come from Slurm's own
# SBATCH_* variables (SBATCH_PARTITION, SBATCH_ACCOUNT, …); CPUS_PER_PART (default 1) sets the
# threads of each part.
set -euo pipefail
if [ $# -lt 3 ]; then
    sed -n '2,11p' "$0" | sed 's/^# \{0,1\}//' >&2
    exit 2
fi
scene=$1 n=$2 output=$3
shift 3
case "$n" in '' | *[!0-9]* | 0) echo "error: N must be a positive number of parts, got '$n'" >&2; exit 2 ;; esac
here=$(cd "$(dirname "$0")" && pwd)
abs() { case "$1" in /*) echo "$1" ;; *) echo "$PWD/$1" ;; esac; }
output=$(abs "$output")
parts_dir=$(abs "${PARTS_DIR:-${output%.*}-parts}")
if [ -f "$scene" ]; then scene=$(abs "$scene"); fi
mkdir -p "$parts_dir"
rm -f "$parts_dir"/part-*.exr
export NEUMANN_SCENE=$scene NEUMANN_PARTS_DIR=$parts_dir NEUMANN_OUTPUT=$output NEUMANN_ARGS="$*"
# A binary named by a relative path is found from the jobs' folders too.
case "${NEUMANN:-neumann}" in */*) NEUMANN=$(abs "$NEUMANN") ;; esac
export NEUMANN=${NEUMANN:-neumann}
array=$(sbatch --parsable --array="1-$n" --cpus-per-task="${CPUS_PER_PART:-1}" \
    --output="$parts_dir/part-%a.log" --export=ALL "$here/render.sbatch")
merge=$(sbatch --parsable --dependency="afterany:$array" --output="$parts_dir/merge.log" --export=ALL "$here/merge.sbatch")
echo "$array $merge"
