#!/usr/bin/env bash
# relMSE at equal time of two builds of hexray, alternated render by render in one run, against
# the reference scenes' deep references with the references' noise subtracted: each scene's
# ratio NEW / OLD of the relMSE summed over the seeds. For a change that moves the error (a
# default, an estimator), where `benches/alternate.sh` measures speed alone.
#
#   benches/builds_equal_time.sh OLD_BINARY NEW_BINARY OUT_DIR
#   METHOD=sppm SEEDS="21 22" SECONDS_EACH=20 benches/builds_equal_time.sh old new out/x
#
# METHOD (vcm), BACKEND (cpu), SIZE (256), SECONDS_EACH (30), SEEDS ("21 22 23 24"), SCENES
# (tncg15_room glass_room cornell_box). Nothing else should run on the machine meanwhile.
set -euo pipefail
cd "$(dirname "$0")/.."
old=$1
new=$2
out=$3
mkdir -p "$out"
. benches/reference_scenes.sh

rows=$out/rows.txt
: > "$rows"
echo "scene build seed relmse_minus_noise iterations" | tee -a "$rows"
for seed in ${SEEDS:-21 22 23 24}; do
    for name in ${SCENES:-tncg15_room glass_room cornell_box}; do
        read -r _ ref noise <<< "$(scene_row "$name")"
        for build in old new; do
            bin=$old
            [ "$build" = new ] && bin=$new
            o=$out/${name}_${build}_$seed.exr
            "$bin" render "scenes/$name.json" --backend "${BACKEND:-cpu}" \
                --method "${METHOD:-vcm}" --width "${SIZE:-256}" --height "${SIZE:-256}" \
                --time "${SECONDS_EACH:-30}" --seed "$seed" --out "$o" 2> "$o.log"
            rel=$("$new" compare "$o" "$ref" --json |
                python3 -c "import json, sys; print(json.load(sys.stdin)['relmse'] - $noise)")
            spp=$(sed -n 's/^rendered \([0-9]*\) spp.*/\1/p' "$o.log")
            echo "$name $build $seed $rel $spp" | tee -a "$rows"
        done
    done
done

echo
echo "new / old, relMSE summed over the seeds (and each seed's ratio)"
python3 - "$rows" <<'PY'
import collections, sys
rel = collections.defaultdict(dict)
for line in list(open(sys.argv[1]))[1:]:
    name, build, seed, r, _ = line.split()
    rel[(name, seed)][build] = float(r)
names = []
for name, _ in rel:
    if name not in names:
        names.append(name)
for name in names:
    seeds = [k for k in rel if k[0] == name]
    old = sum(rel[k]["old"] for k in seeds)
    new = sum(rel[k]["new"] for k in seeds)
    each = " ".join(f"{rel[k]['new'] / rel[k]['old']:.3f}" for k in seeds)
    print(f"{name} {new / old:.3f} ({each})")
PY
