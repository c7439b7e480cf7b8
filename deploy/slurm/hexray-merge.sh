#!/usr/bin/env bash
# Merges the parts of hexray-array.sh (run by submit.sh after the whole array succeeded).
#SBATCH --job-name=hexray-merge
#SBATCH --cpus-per-task=1
#SBATCH --time=00:10:00
set -euo pipefail
: "${OUTDIR:=parts}" "${HEXRAY:=hexray}"
shopt -s nullglob
parts=()
for f in "$OUTDIR"/part_*.exr; do
    case "$f" in *_var.exr) ;; *) parts+=("$f") ;; esac
done
exec "$HEXRAY" merge "${parts[@]}" -o "$OUTDIR/merged.exr"
