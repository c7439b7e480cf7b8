#!/usr/bin/env bash
# configs: old | K:Q:FLOOR  (tuning build /work/bin/hexray-tune reads HEXRAY_K, HEXRAY_Q, HEXRAY_FLOOR)
set -u
cd /work/main
. benches/reference_scenes.sh
out=/work/calib/out4; mkdir -p $out
rows=${ROWS:-/work/calib/rows4.txt}
for seed in ${SEEDS:-14 15}; do
 for name in ${SCENES:-tncg15_room glass_room cornell_box}; do
  read -r _ ref noise <<< "$(scene_row "$name")"
  for c in ${CONFIGS}; do
    o=$out/${name}_${c//:/_}_$seed.exr
    if [ $c = old ]; then bin=/work/bin/hexray-22a1503; envs="X=1"; else
      IFS=: read -r k q f g <<< "$c"; bin=/work/bin/hexray-tune2; envs="HEXRAY_K=$k HEXRAY_Q=$q HEXRAY_FLOOR=$f HEXRAY_GAMMA=${g:-1}"; fi
    env $envs $bin render scenes/$name.json --backend cpu --method vcm --width 256 --height 256 --time ${SECS:-20} --seed $seed --out $o 2> $o.log
    rel=$($bin compare $o $ref --json | python3 -c "import json,sys; print(json.load(sys.stdin)['relmse'] - $noise)")
    it=$(sed -n 's/^rendered \([0-9]*\) spp.*/\1/p' $o.log)
    echo "$name $c $seed $rel $it" | tee -a $rows
  done
 done
done
