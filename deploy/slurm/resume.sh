#!/usr/bin/env bash
# Resubmits array tasks that failed or were stopped, then the merge after them:
#   resume.sh ARRAY_JOB MERGE_JOB TASKS [sbatch options for the array]   e.g. resume.sh 1233 1234 3,7
# (ARRAY_JOB and MERGE_JOB are what submit.sh printed). Each task resumes from its part_K.film
# (see hexray-array.sh). The merge queued by submit.sh can no longer run (a task of its afterok
# failed), so it is cancelled and queued again, to run once every task of the first array has
# ended and every resubmitted task has succeeded. Prints: NEW_ARRAY_JOB NEW_MERGE_JOB.
set -euo pipefail
if [ $# -lt 3 ]; then
    echo "usage: $0 ARRAY_JOB MERGE_JOB TASKS [sbatch options...]" >&2
    exit 2
fi
here=$(cd "$(dirname "$0")" && pwd)
old_array=$1 old_merge=$2 tasks=$3
shift 3
: "${OUTDIR:=parts}"
export OUTDIR
mkdir -p "$OUTDIR"
scancel "$old_merge"
array=$(sbatch --parsable --export=ALL --output="$OUTDIR/slurm-%A_%a.out" --array="$tasks" "$@" \
    "$here/hexray-array.sh")
merge=$(sbatch --parsable --export=ALL --output="$OUTDIR/slurm-merge-%j.out" \
    --dependency="afterany:$old_array,afterok:$array" "$here/hexray-merge.sh")
echo "$array $merge"
