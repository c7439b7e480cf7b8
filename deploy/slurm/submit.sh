#!/usr/bin/env bash
# Queues the part array, then the merge with afterok: the merge runs only if every part succeeded.
#   submit.sh [sbatch options for the array, e.g. --array=1-16 --cpus-per-task=4 --gres=gpu:1]
# Paths (SCENE, OUTDIR, HEXRAY) are taken from the directory it is run in. Prints the two job ids:
# ARRAY MERGE. A task that failed or was stopped: resume.sh MERGE ARRAY_TASKS.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
: "${OUTDIR:=parts}"
export OUTDIR
# Slurm opens --output before the job starts; a missing folder fails the job (JobLaunchFailure).
mkdir -p "$OUTDIR"
array=$(sbatch --parsable --export=ALL --output="$OUTDIR/slurm-%A_%a.out" "$@" \
    "$here/hexray-array.sh")
merge=$(sbatch --parsable --export=ALL --output="$OUTDIR/slurm-merge-%j.out" \
    --dependency=afterok:"$array" "$here/hexray-merge.sh")
echo "$array $merge"
