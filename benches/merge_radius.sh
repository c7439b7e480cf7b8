#!/usr/bin/env bash
# The merge radius at equal time: relMSE of vcm (or sppm) renders at several initial radii and
# alphas, each a share of the scene's bounding-sphere radius, against the scenes' deep
# references, with the references' noise subtracted, and each configuration's ratio to the
# first one's (summed over the seeds).
#
#   benches/merge_radius.sh                     # 256x256, 30 s, seeds 11 12, three scenes
#   SIZE=512 SECONDS_EACH=10 SEEDS="5 6" CONFIGS="0.003,0.75 0.005,0.75" benches/merge_radius.sh
#
# CONFIGS: "factor,alpha ..." (the first is the baseline; default "0.003,0.75 0.01,0.75
# 0.01,0.6667 0.015,0.6667"). SCENES: names among tncg15_room glass_room cornell_box. A render
# larger than its reference (512x512 against 256x256) is compared as block means
# (`hexray compare`). METHOD (default vcm), HEXRAY (default target/release/hexray). Nothing else
# should run on the machine meanwhile: the renders are at equal time.
set -euo pipefail
cd "$(dirname "$0")/.."
hexray=${HEXRAY:-target/release/hexray}
size=${SIZE:-256}
seconds=${SECONDS_EACH:-30}
method=${METHOD:-vcm}
out=${OUT:-out/merge_radius}
mkdir -p "$out"

. benches/reference_scenes.sh

rows=$out/rows.txt
: > "$rows"
echo "scene factor alpha seed relmse_minus_noise iterations"
for seed in ${SEEDS:-11 12}; do
    for name in ${SCENES:-tncg15_room glass_room cornell_box}; do
        read -r radius ref noise <<< "$(scene_row "$name")"
        for c in ${CONFIGS:-0.003,0.75 0.01,0.75 0.01,0.6667 0.015,0.6667}; do
            IFS=, read -r f a <<< "$c"
            r=$(python3 -c "print($f * $radius)")
            o=$out/${name}_${size}_${f}_${a}_$seed.exr
            "$hexray" render "scenes/$name.json" --backend cpu --method "$method" --width "$size" \
                --height "$size" --time "$seconds" --seed "$seed" --radius "$r" --alpha "$a" \
                --out "$o" 2> "$o.log"
            rel=$("$hexray" compare "$o" "$ref" --json |
                python3 -c "import json, sys; print(json.load(sys.stdin)['relmse'] - $noise)")
            spp=$(sed -n 's/^rendered \([0-9]*\) spp.*/\1/p' "$o.log")
            echo "$name $f $a $seed $rel $spp" | tee -a "$rows"
        done
    done
done

echo
echo "ratio to ${CONFIGS%% *} (sum over seeds)"
python3 - "$rows" <<'PY'
import collections, sys
sums = collections.defaultdict(float)
order = []
for line in open(sys.argv[1]):
    name, f, a, seed, rel, spp = line.split()
    sums[(name, f, a)] += float(rel)
    if (f, a) not in order:
        order.append((f, a))
names = sorted({k[0] for k in sums}, key=lambda n: ["tncg15_room", "glass_room", "cornell_box"].index(n))
print("factor alpha " + " ".join(names) + " geometric_mean")
for f, a in order:
    ratios = [sums[(n, f, a)] / sums[(n,) + order[0]] for n in names]
    g = 1.0
    for r in ratios:
        g *= r
    print(f, a, " ".join(f"{r:.2f}" for r in ratios), f"{g ** (1 / len(ratios)):.2f}")
PY
