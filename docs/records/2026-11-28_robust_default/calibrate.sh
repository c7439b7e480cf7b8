#!/usr/bin/env bash
set -u
cd /work/main
. benches/reference_scenes.sh
out=/work/calib/out2; mkdir -p $out
rows=/work/calib/rows2.txt
for seed in ${SEEDS:-12 13}; do
 for name in tncg15_room glass_room cornell_box; do
  read -r _ ref noise <<< "$(scene_row "$name")"
  for c in ${CONFIGS:-old 0.03:0.9:fp 0.031:0.5:fp 0.031:0.5:uni 0.02:0.9:fp}; do
    o=$out/${name}_${c//:/_}_$seed.exr
    if [ $c = old ]; then bin=/work/bin/hexray-22a1503; envs="X=1"; else
      IFS=: read -r k q u <<< "$c"; bin=/work/bin/hexray-k2; envs="HEXRAY_K=$k HEXRAY_Q=$q"; [ $u = uni ] && envs="$envs HEXRAY_UNIFORM=1"; fi
    env $envs $bin render scenes/$name.json --backend cpu --method vcm --width 256 --height 256 --time ${SECS:-20} --seed $seed --out $o 2> $o.log
    rel=$($bin compare $o $ref --json | python3 -c "import json,sys; print(json.load(sys.stdin)['relmse'] - $noise)")
    it=$(sed -n 's/^rendered \([0-9]*\) spp.*/\1/p' $o.log)
    echo "$name $c $seed $rel $it" | tee -a $rows
  done
 done
done
