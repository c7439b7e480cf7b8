#!/usr/bin/env bash
# Queues the part array, then the merge with afterok: the merge runs only if every part succeeded
# (a failed task can be resubmitted alone: sbatch --array=K hexray-array.sh; same seed, same file).
set -euo pipefail
cd "$(dirname "$0")"
array=$(sbatch --parsable --export=ALL hexray-array.sh)
sbatch --dependency=afterok:"$array" --export=ALL hexray-merge.sh
