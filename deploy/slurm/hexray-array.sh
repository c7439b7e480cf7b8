#!/usr/bin/env bash
# One part per array task: task k renders seed k into OUTDIR/part_k.exr. Submit with submit.sh,
# which also queues the merge to run once every part has succeeded.
#
# A task stopped with SIGTERM (`scancel --signal=TERM --batch JOB_K`, the time limit, preemption)
# keeps its samples: hexray finishes the pass, writes part_k.exr/.film and exits 143. Submitting
# task k again (sbatch --array=K, or resume.sh) resumes it from part_k.film to SPP in total, the
# same samples an uninterrupted task would have taken; a finished part is left as it is.
#SBATCH --job-name=hexray-part
#SBATCH --array=1-8
#SBATCH --cpus-per-task=8
#SBATCH --time=01:00:00
# SIGTERM to hexray 5 minutes before the time limit: it writes what it has, and a resubmitted task
# continues from there (at the limit itself Slurm sends SIGTERM too, then SIGKILL after KillWait).
#SBATCH --signal=B:TERM@300
set -euo pipefail
: "${SCENE:=scenes/tncg15_room.json}" "${SPP:=256}" "${OUTDIR:=parts}" "${HEXRAY:=hexray}"
mkdir -p "$OUTDIR"
part="$OUTDIR/part_${SLURM_ARRAY_TASK_ID}"
threads=${SLURM_CPUS_PER_TASK:-1}
# `exec`: hexray replaces this shell and is itself the batch step, so every SIGTERM Slurm sends to
# the batch step reaches hexray. Without it, the signal kills bash and, where Slurm tracks
# processes by parentage (proctrack/linuxproc), hexray is orphaned: it renders on outside the job
# and never writes.
if [ -f "$part.film" ]; then
    # EXTRA_ARGS of the first render (method, size) come from the film; RESUME_ARGS may add
    # --backend, --checkpoint.
    exec "$HEXRAY" render --resume "$part.exr" --spp "$SPP" --threads "$threads" --variance \
        --quiet ${RESUME_ARGS:-}
fi
# --backend auto takes the node's GPU when it has one (request it with --gres=gpu:1).
exec "$HEXRAY" render "$SCENE" --seed "$SLURM_ARRAY_TASK_ID" --spp "$SPP" \
    --threads "$threads" --variance --quiet --out "$part.exr" ${EXTRA_ARGS:-}
