#!/usr/bin/env bash
# Two builds' CPU throughput, measured alternately in one run: `hexray bench --backend cpu
# --threads 2` of OLD and NEW, the order swapped each round, each round's JSON in OUT, then the
# median and range of NEW / OLD camera paths/s per scene. These machines drift by tens of percent
# between hours, so only ratios measured side by side count (CONTRIBUTING.md).
#
#   benches/alternate.sh OLD_BINARY NEW_BINARY ROUNDS OUT_DIR
#   BENCH_ARGS="--spp 4 --method vcm" benches/alternate.sh ...   # other bench options
set -euo pipefail
old=$1; new=$2; rounds=$3; out=$4
cd "$(dirname "$0")/.."
mkdir -p "$out"
for r in $(seq 1 "$rounds"); do
    if [ $((r % 2)) = 1 ]; then order="old new"; else order="new old"; fi
    for b in $order; do
        bin=$old; [ "$b" = new ] && bin=$new
        # shellcheck disable=SC2086
        "$bin" bench --backend cpu --threads 2 ${BENCH_ARGS:---spp 64} --out "$out/${b}_$r.json" \
            > "$out/${b}_$r.txt" 2>&1
    done
done
python3 - "$out" "$rounds" <<'PY'
import json, statistics, sys
out, rounds = sys.argv[1], int(sys.argv[2])
def rates(path):
    return {r["scene"]: r["camera_paths_per_second"] for r in json.load(open(path))["rows"]}
ratios = {}
for r in range(1, rounds + 1):
    old, new = rates(f"{out}/old_{r}.json"), rates(f"{out}/new_{r}.json")
    for scene in old:
        ratios.setdefault(scene, []).append(new[scene] / old[scene])
for scene, v in ratios.items():
    print(f"{scene}: new/old {statistics.median(v):.3f} (range {min(v):.3f} - {max(v):.3f}, "
          f"{len(v)} alternations)")
PY
