#!/usr/bin/env bash
# relMSE at equal time, hexray's methods against Mitsuba 3's path tracer, alternating in one run
# (these machines drift by tens of percent between hours, so only a ratio measured this way
# counts).
#
#   benches/methods_vs_mitsuba.sh [SCENE_NAME ...]     (default: tncg15_room glass_room)
#
# Per scene and alternation: Mitsuba `path` (llvm_ad_rgb, all cores) renders N samples, N sized
# in a first calibration render to take about SECONDS (default 30); then each hexray method in
# METHODS (default "path bdpt vcm sppm", CPU backend, BACKEND to change) renders for exactly as
# long as that Mitsuba render took (`--time`), 256x256. Every image is compared with the scene's
# deep reference out/methods/refs/NAME_256.exr (`docs/figures/methods.sh references`, or the committed GPU
# references copied there: tests/data/references/README.md), whose own noise
# (mean var_r / (r^2 + 0.01)) is subtracted from every relMSE. ALTERNATIONS (default 3) rounds.
# Prints one table row per render and, per method, the median ratio to Mitsuba and its range.
# Needs MITSUBA_PYTHON (default $HOME/mi/bin/python) with Mitsuba 3; see ../shared/mitsuba/.
set -euo pipefail
cd "$(dirname "$0")/.."
hexray=${HEXRAY:-target/release/hexray}
python=${MITSUBA_PYTHON:-$HOME/mi/bin/python}
seconds=${SECONDS_PER_RENDER:-30}
methods=${METHODS:-path bdpt vcm sppm}
backend=${BACKEND:-cpu}
rounds=${ALTERNATIONS:-3}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
scenes=("$@")
[ ${#scenes[@]} -gt 0 ] || scenes=(tncg15_room glass_room)

relmse() { # IMAGE REF -> relMSE minus the reference's noise
    "$hexray" compare "$1" "$2" --json |
        python3 -c 'import json,sys; c=json.load(sys.stdin); print(c["relmse"] - (c["relmse_reference_noise"] or 0))'
}

echo "scene,round,renderer,method,seconds,relmse_minus_ref_noise" > "$work/rows.csv"
for name in "${scenes[@]}"; do
    scene=scenes/$name.json ref=out/methods/refs/${name}_256.exr
    [ -f "$ref" ] || { echo "missing $ref: run docs/figures/methods.sh references" >&2; exit 1; }
    noise=$("$hexray" compare "$ref" "$ref" --json |
        python3 -c 'import json,sys; print(json.load(sys.stdin)["relmse_reference_noise"])')
    # Calibration: Mitsuba's samples per second on this scene, from 64 spp.
    rate=$("$python" benches/mitsuba_curve.py "$scene" --ref "$ref" --spp 64 | tail -1 |
        awk -F, '{print 64 / $4}')
    spp=$(python3 -c "print(max(1, round($rate * $seconds)))")
    echo "== $name: Mitsuba path at $spp spp (about $seconds s), reference noise $noise" >&2
    for round in $(seq 1 "$rounds"); do
        row=$("$python" benches/mitsuba_curve.py "$scene" --ref "$ref" --spp "$spp" \
            --seed "$((2000 + 100 * round))" | tail -1)
        t=$(echo "$row" | cut -d, -f4)
        e=$(echo "$row" | awk -F, -v n="$noise" '{print $6 - n}')
        echo "$name,$round,mitsuba,path,$t,$e" | tee -a "$work/rows.csv" >&2
        for m in $methods; do
            "$hexray" render "$scene" --backend "$backend" --method "$m" --time "$t" \
                --width 256 --height 256 --seed "$round" --out "$work/$m.exr" --quiet
            e=$(relmse "$work/$m.exr" "$ref")
            echo "$name,$round,hexray $backend,$m,$t,$e" | tee -a "$work/rows.csv" >&2
        done
    done
done
python3 - "$work/rows.csv" <<'PY'
import csv, statistics, sys
rows = list(csv.DictReader(open(sys.argv[1])))
print("| scene | renderer | method | relMSE (median of rounds) | ratio to Mitsuba path: median (range) |")
print("| --- | --- | --- | --- | --- |")
for scene in dict.fromkeys(r["scene"] for r in rows):
    rs = [r for r in rows if r["scene"] == scene]
    mitsuba = {r["round"]: float(r["relmse_minus_ref_noise"]) for r in rs if r["renderer"] == "mitsuba"}
    for key in dict.fromkeys((r["renderer"], r["method"]) for r in rs):
        es = [(r["round"], float(r["relmse_minus_ref_noise"])) for r in rs if (r["renderer"], r["method"]) == key]
        ratios = [e / mitsuba[k] for k, e in es]
        med = statistics.median(e for _, e in es)
        print(f"| {scene} | {key[0]} | {key[1]} | {med:.3e} | {statistics.median(ratios):.3f} ({min(ratios):.3f} – {max(ratios):.3f}) |")
print()
print("seconds per render: " + ", ".join(sorted({r['seconds'] for r in rows if r['renderer'] == 'mitsuba'})))
PY
