#!/usr/bin/env bash
# relMSE of hexray's methods at equal time, one render each per scene and seed, against the
# scenes' deep references with the references' noise subtracted, and each method's ratio to the
# first one's (the geometric mean over the scenes too). No Mitsuba: for ratios between hexray's
# own methods on one backend (benches/methods_vs_mitsuba.sh alternates with Mitsuba).
#
#   benches/methods_equal_time.sh                                  # CPU, path vcm vcm-full sppm
#   BACKEND=gpu METHODS="path vcm sppm" SECONDS_EACH=30 benches/methods_equal_time.sh
#
# METHODS (the first is the baseline), BACKEND (cpu or gpu), SCENES (among tncg15_room
# glass_room cornell_box), SIZE (256; 512 is compared as 2x2 block means), SECONDS_EACH (30),
# SEEDS (11), HEXRAY (target/release/hexray), OUT (out/methods_equal_time). Nothing else should
# run on the machine meanwhile.
set -euo pipefail
cd "$(dirname "$0")/.."
hexray=${HEXRAY:-target/release/hexray}
size=${SIZE:-256}
seconds=${SECONDS_EACH:-30}
backend=${BACKEND:-cpu}
out=${OUT:-out/methods_equal_time}
mkdir -p "$out"

. benches/reference_scenes.sh

rows=$out/rows.txt
: > "$rows"
echo "scene method seed relmse_minus_noise iterations"
for seed in ${SEEDS:-11}; do
    for name in ${SCENES:-tncg15_room glass_room cornell_box}; do
        read -r _ ref noise <<< "$(scene_row "$name")"
        for m in ${METHODS:-path vcm vcm-full sppm}; do
            o=$out/${name}_${backend}_${size}_${m}_$seed.exr
            "$hexray" render "scenes/$name.json" --backend "$backend" --method "$m" \
                --width "$size" --height "$size" --time "$seconds" --seed "$seed" \
                --out "$o" 2> "$o.log"
            rel=$("$hexray" compare "$o" "$ref" --json |
                python3 -c "import json, sys; print(json.load(sys.stdin)['relmse'] - $noise)")
            spp=$(sed -n 's/^rendered \([0-9]*\) spp.*/\1/p' "$o.log")
            echo "$name $m $seed $rel $spp" | tee -a "$rows"
        done
    done
done

echo
echo "ratio to ${METHODS%% *} (sum over seeds)"
python3 - "$rows" <<'PY'
import collections, sys
sums = collections.defaultdict(float)
order = []
for line in open(sys.argv[1]):
    name, m, seed, rel, spp = line.split()
    sums[(name, m)] += float(rel)
    if m not in order:
        order.append(m)
names = sorted({k[0] for k in sums}, key=lambda n: ["tncg15_room", "glass_room", "cornell_box"].index(n))
print("method " + " ".join(names) + " geometric_mean")
for m in order:
    ratios = [sums[(n, m)] / sums[(n, order[0])] for n in names]
    g = 1.0
    for r in ratios:
        g *= r
    print(m, " ".join(f"{r:.3f}" for r in ratios), f"{g ** (1 / len(ratios)):.3f}")
PY
