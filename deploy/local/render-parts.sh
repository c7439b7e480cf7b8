#!/usr/bin/env bash
# Renders one scene as PARTS independent parts on this host, in parallel processes, and merges
# them: render-parts.sh SCENE PARTS SPP OUTDIR [extra `hexray render` arguments...]
#
# Part k (1..PARTS) uses seed SEED0 + k, so parts never share samples; a part that fails can be
# re-run alone with the same command and gives the same file. Writes OUTDIR/part_<seed>.exr
# (+ _var.exr, .png) and OUTDIR/merged.exr (+ merged_var.exr, merged.png).
#
# Environment: HEXRAY (the binary, default target/release/hexray), JOBS (parallel processes,
# default: the number of cores), THREADS (threads per process, default: cores / JOBS),
# SEED0 (default 0).
set -euo pipefail

if [ $# -lt 4 ]; then
    echo "usage: $0 SCENE PARTS SPP OUTDIR [extra hexray render arguments...]" >&2
    exit 2
fi
scene=$1 parts=$2 spp=$3 outdir=$4
shift 4
hexray=${HEXRAY:-target/release/hexray}
cores=$(nproc)
jobs=${JOBS:-$cores}
threads=${THREADS:-$(( cores / jobs > 0 ? cores / jobs : 1 ))}
seed0=${SEED0:-0}
mkdir -p "$outdir"

seeds=$(seq $((seed0 + 1)) $((seed0 + parts)))
# xargs exits non-zero if any part failed; set -e then stops before the merge.
printf '%s\n' $seeds | xargs -P "$jobs" -I{} \
    "$hexray" render "$scene" --seed {} --spp "$spp" --threads "$threads" --variance --quiet \
    --out "$outdir/part_{}.exr" "$@"

files=()
for s in $seeds; do files+=("$outdir/part_$s.exr"); done
"$hexray" merge "${files[@]}" -o "$outdir/merged.exr"
