#!/usr/bin/env bash
# One part per array task: task k renders seed k. Submit with submit.sh, which also queues the
# merge to run once every part has succeeded.
#SBATCH --job-name=hexray-part
#SBATCH --array=1-8
#SBATCH --cpus-per-task=8
#SBATCH --time=01:00:00
#SBATCH --output=parts/slurm-%A_%a.out
set -euo pipefail
: "${SCENE:=scenes/tncg15_room.json}" "${SPP:=256}" "${OUTDIR:=parts}" "${HEXRAY:=hexray}"
mkdir -p "$OUTDIR"
# --backend auto takes the node's GPU when it has one (request it with --gres=gpu:1).
"$HEXRAY" render "$SCENE" --seed "$SLURM_ARRAY_TASK_ID" --spp "$SPP" \
    --threads "$SLURM_CPUS_PER_TASK" --variance --quiet \
    --out "$OUTDIR/part_${SLURM_ARRAY_TASK_ID}.exr" ${EXTRA_ARGS:-}
