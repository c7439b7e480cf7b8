#!/usr/bin/env bash
# The 2020 course report's table: tncg15_room at 800x800 with (spp, shadow rays per vertex) =
# (50, 2), (25, 2), (5, 1), (5, 10), on each backend: render time and relMSE against a long
# reference. Usage: docs/figures/shadow_rays.sh REFERENCE.exr [backends, default "cpu gpu"]
# Make the reference first (a few minutes on 2 cores):
#   hexray reference scenes/tncg15_room.json --backend cpu --width 800 --height 800 --spp 512 \
#       --seed 9001 --out out/tncg15_800_ref.exr
# Run it from the repository's root. Writes docs/figures/shadow_rays/table.csv. relMSE_corrected subtracts the reference's own noise
# (E (x − r)² = var_x + var_r), which matters for the longer rows.
set -euo pipefail
ref=$1
backends=${2:-cpu gpu}
hexray=${HEXRAY:-target/release/hexray}
out=docs/figures/shadow_rays
mkdir -p "$out" out/shadow_rays
echo "backend,spp,shadow_rays,seconds,cpu_seconds,relmse,relmse_corrected" > "$out/table.csv.tmp"
for b in $backends; do
    for row in "50 2" "25 2" "5 1" "5 10"; do
        set -- $row
        exr=out/shadow_rays/${b}_${1}spp_${2}rays.exr
        # cpu_seconds (user + system time of the process, all threads, JIT included) is what
        # the render cost even when other work shares the cores and stretches the wall time.
        log=$(/usr/bin/time -f "cpu %U %S" "$hexray" render scenes/tncg15_room.json --backend "$b" --width 800 --height 800 \
            --spp "$1" --light-samples "$2" --seed 7 --variance --out "$exr" 2>&1)
        secs=$(sed -n 's/^rendered .* in \([0-9.]*\) s .*/\1/p' <<<"$log")
        cpu=$(awk '/^cpu /{print $2 + $3}' <<<"$log")
        json=$("$hexray" compare "$exr" "$ref" --json)
        rel=$(python3 -c 'import json,sys; j=json.loads(sys.argv[1]); print(j["relmse"], j["relmse"]-j["relmse_reference_noise"])' "$json")
        echo "$b,$1,$2,$secs,$cpu,${rel/ /,}" | tee -a "$out/table.csv.tmp"
    done
done
mv "$out/table.csv.tmp" "$out/table.csv"
