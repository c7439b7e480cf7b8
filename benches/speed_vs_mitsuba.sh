#!/usr/bin/env bash
# CPU camera paths per second, hexray's path tracer against Mitsuba 3's `path` (llvm_ad_rgb), side
# by side in one run, alternating (these machines drift by tens of percent between hours, so only
# a ratio measured this way counts).
#
#   benches/speed_vs_mitsuba.sh [SCENE_NAME ...]   (default: tncg15_room cornell_box glass_room)
#   benches/speed_vs_mitsuba.sh tncg15_room bunny_room perf/bunny_room_1m   # the mesh scenes
#
# A scene of scenes/perf/ whose mesh is generated (bunny_room_1m) has it generated first.
# Per round and scene: `hexray bench` (path, CPU, THREADS threads, 256x256, SPP samples, after its
# warm-up; its render time only) and Mitsuba's render call of the same scene, size and samples
# (after a warm-up render that compiles its kernels; ../shared/mitsuba/mitsuba_side.py time), in
# alternating order (hexray first in odd rounds, Mitsuba first in even ones). ROUNDS (default 5)
# rounds. Prints one CSV row per render, then per scene the median ratio hexray / Mitsuba of paths
# per second and its range over the rounds, with the date and the machine.
# Needs MITSUBA_PYTHON (default $HOME/mi/bin/python) with Mitsuba 3 (../shared/mitsuba/README.md)
# and MITSUBA_SIDE (default ../shared/mitsuba/mitsuba_side.py). Never needed by the build or tests.
set -euo pipefail
cd "$(dirname "$0")/.."
hexray=${HEXRAY:-target/release/hexray}
python=${MITSUBA_PYTHON:-$HOME/mi/bin/python}
side=${MITSUBA_SIDE:-../shared/mitsuba/mitsuba_side.py}
spp=${SPP:-128}
threads=${THREADS:-2}
rounds=${ROUNDS:-5}
scenes=("$@")
[ ${#scenes[@]} -gt 0 ] || scenes=(tncg15_room cornell_box glass_room)
for name in "${scenes[@]}"; do
    if grep -q 'generated/bunny_1m.ply' "scenes/$name.json" && [ ! -f scenes/models/generated/bunny_1m.ply ]; then
        python3 scenes/models/make_large_mesh.py > /dev/null
    fi
done
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

run_hexray() { # NAME ROUND
    "$hexray" bench "scenes/$1.json" --backend cpu --method path --spp "$spp" \
        --threads "$threads" --out "$work/h.json" > /dev/null 2>&1
    python3 -c "import json,sys; r=json.load(open(sys.argv[1]))['rows'][0]; print('%s,%s,hexray,%.4f,%.0f' % (sys.argv[2], sys.argv[3], r['seconds'], r['camera_paths_per_second']))" \
        "$work/h.json" "$1" "$2"
}
run_mitsuba() { # NAME ROUND
    "$python" "$side" time "scenes/$1.json" --res 256 --spp "$spp" --repeat 1 |
        python3 -c "import json,sys; r=json.loads(sys.stdin.read()); print('%s,%s,mitsuba,%.4f,%d' % (sys.argv[1], sys.argv[2], r['seconds'], r['paths_per_s']))" "$1" "$2"
}

echo "# $(date -u +%Y-%m-%dT%H:%MZ), $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs), $(nproc) cores; hexray $(git rev-parse --short HEAD), $spp spp, 256x256, $threads threads"
echo "scene,round,renderer,seconds,paths_per_second" | tee "$work/rows.csv"
for round in $(seq 1 "$rounds"); do
    for name in "${scenes[@]}"; do
        if [ $((round % 2)) -eq 1 ]; then
            run_hexray "$name" "$round" | tee -a "$work/rows.csv"
            run_mitsuba "$name" "$round" | tee -a "$work/rows.csv"
        else
            run_mitsuba "$name" "$round" | tee -a "$work/rows.csv"
            run_hexray "$name" "$round" | tee -a "$work/rows.csv"
        fi
    done
done
python3 - "$work/rows.csv" <<'PY'
import csv, statistics, sys
rows = list(csv.DictReader(open(sys.argv[1])))
print("\nscene,median ratio hexray/mitsuba (paths/s),min,max,rounds")
for scene in dict.fromkeys(r["scene"] for r in rows):
    by = {}
    for r in rows:
        if r["scene"] == scene:
            by.setdefault(r["round"], {})[r["renderer"]] = float(r["paths_per_second"])
    ratios = [v["hexray"] / v["mitsuba"] for v in by.values() if len(v) == 2]
    print(f"{scene},{statistics.median(ratios):.3f},{min(ratios):.3f},{max(ratios):.3f},{len(ratios)}")
# Each renderer's median paths/s, and its cost per path over the first scene's (same renderer).
print("\nscene,renderer,median M paths/s,cost per path / " + rows[0]["scene"])
for renderer in ("hexray", "mitsuba"):
    med = {}
    for scene in dict.fromkeys(r["scene"] for r in rows):
        med[scene] = statistics.median(float(r["paths_per_second"]) for r in rows
                                       if r["scene"] == scene and r["renderer"] == renderer)
        print(f"{scene},{renderer},{med[scene] / 1e6:.3f},{med[rows[0]['scene']] / med[scene]:.2f}")
PY
