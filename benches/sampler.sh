#!/usr/bin/env bash
# The samplers side by side: path tracing's relMSE against samples per pixel and
# against render time, independent against sobol, on the three reference scenes at 256x256 on the
# CPU, and what a Sobol point costs (camera paths/s on the CPU and on the GPU adapter).
#
#   benches/sampler.sh [OUT]      (default OUT: docs/figures/sampling)
#
# Per scene and seed (SEEDS, default "1 2 3"): `hexray curve --sampler independent,sobol` (one
# series per sampler, relMSE after 1, 2, 4, ... spp until SECONDS, default 6, of render time each,
# against tests/data/references). Then `hexray bench --sampler independent,sobol,independent,sobol`
# (BACKENDS, default cpu,gpu; 256x256, 32 spp): each sampler twice, alternating.
# Writes OUT/<scene>_seed<k>/ (curve.csv; the first seed's charts too), OUT/bench.txt, and
# OUT/summary.md: the relMSE ratio sobol / independent at each spp per scene (the geometric mean
# over seeds, and its range), and the cost per camera path. About 4.5 minutes on 2 cores with lavapipe. A benchmark:
# it asserts nothing.
set -euo pipefail
cd "$(dirname "$0")/.."
hexray=${HEXRAY:-target/release/hexray}
out=${1:-docs/figures/sampling}
seeds=${SEEDS:-1 2 3}
seconds=${SECONDS_PER_SERIES:-6}
backends=${BACKENDS:-cpu,gpu}
mkdir -p "$out"
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-/tmp}

reference() {
    case "$1" in
        cornell_box) echo tests/data/references/cornell_box_256.npy ;;
        *) echo "tests/data/references/h100/$1_256.exr" ;;
    esac
}

start=$(date +%s)
for scene in cornell_box tncg15_room glass_room; do
    for seed in $seeds; do
        "$hexray" curve "scenes/$scene.json" --reference "$(reference "$scene")" \
            --sampler independent,sobol --seed "$seed" --time "$seconds" \
            --out "$out/${scene}_seed$seed" 2> "$out/${scene}_seed$seed.log"
    done
done
"$hexray" bench scenes/cornell_box.json scenes/tncg15_room.json scenes/glass_room.json \
    --backend "$backends" --sampler independent,sobol,independent,sobol --spp 32 \
    --out "$out/bench.json" 2> /dev/null > "$out/bench.txt"
elapsed=$(( $(date +%s) - start ))
# The charts of the first seed only, as PNG (the others' curves stay as CSV).
first=${seeds%% *}
rm -f "$out"/*_seed*/relmse_vs_*.svg
for d in "$out"/*_seed*/; do
    case "$d" in *_seed"$first"/) ;; *) rm -f "$d"relmse_vs_*.png ;; esac
done

python3 - "$out" "$elapsed" $seeds <<'PY'
import csv, json, math, statistics, subprocess, sys
out, elapsed, seeds = sys.argv[1], int(sys.argv[2]), sys.argv[3:]
scenes = ["cornell_box", "tncg15_room", "glass_room"]
lines = []
report = json.load(open(f"{out}/bench.json"))
lines.append(f"Measured {report['date_utc']} on {report['machine']}, hexray "
             f"{subprocess.run(['git', 'rev-parse', '--short', 'HEAD'], capture_output=True, text=True).stdout.strip()}, "
             f"in {elapsed} s by `benches/sampler.sh`. Path tracing, CPU, 256x256; seeds {', '.join(seeds)}.\n")
lines.append("relMSE of sobol over relMSE of independent at equal spp (geometric mean over the seeds; range):\n")
spps = [4, 16, 64, 256]
lines.append("| scene | " + " | ".join(f"{s} spp" for s in spps) + " |")
lines.append("| --- |" + " --- |" * len(spps))
for scene in scenes:
    cells = []
    for spp in spps:
        ratios = []
        for seed in seeds:
            rows = list(csv.DictReader(open(f"{out}/{scene}_seed{seed}/curve.csv")))
            by = {r["backend"]: r for r in rows if int(r["spp"]) == spp}
            ind = [r for k, r in by.items() if k.endswith("independent")]
            sob = [r for k, r in by.items() if k.endswith("sobol")]
            if ind and sob:
                ratios.append(float(sob[0]["relmse"]) / float(ind[0]["relmse"]))
        if len(ratios) == len(seeds):
            g = math.exp(sum(map(math.log, ratios)) / len(ratios))
            cells.append(f"{g:.2f} ({min(ratios):.2f}–{max(ratios):.2f})")
        else:
            cells.append("–")
    lines.append(f"| {scene} | " + " | ".join(cells) + " |")
lines.append("\nCamera paths/s (M), each sampler twice, alternating (`hexray bench`, 32 spp):\n")
lines.append("| scene | backend | independent | sobol | sobol's cost per path |")
lines.append("| --- | --- | --- | --- | --- |")
rows = report["rows"]
for scene in scenes:
    for be in ["cpu", "gpu"]:
        ind = [r["camera_paths_per_second"] for r in rows if r["scene"] == scene and r["backend"] == be and r["sampler"] == "independent"]
        sob = [r["camera_paths_per_second"] for r in rows if r["scene"] == scene and r["backend"] == be and r["sampler"] == "sobol"]
        if ind and sob:
            i, s = statistics.mean(ind), statistics.mean(sob)
            lines.append(f"| {scene} | {be} | {i/1e6:.3f} | {s/1e6:.3f} | {100*(i/s-1):+.1f} % |")
devices = sorted({f"{r['backend']}: {r['device']}" for r in rows})
lines.append("\n" + "; ".join(devices))
open(f"{out}/summary.md", "w").write("\n".join(lines) + "\n")
print("\n".join(lines))
PY
