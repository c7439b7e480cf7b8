#!/bin/bash
# equal-time vcm: uniform vs adaptive M
hx=/work/main/target/release/hexray
ref=${REF:-/work/main/tests/data/references/h100/tncg15_room_256.exr}
T=${T:-4}
scene=${SCENE:-/work/main/scenes/tncg15_room.json}
for seed in 1 2 3; do
  line="seed $seed"
  $hx render $scene --method ${METHOD:-vcm} --width ${SIDE:-256} --height ${SIDE:-256} --time $T --seed $seed -q --out /tmp/e_u.exr
  u=$($hx compare /tmp/e_u.exr $ref | awk '/^relMSE/ {print $2}')
  line="$line uniform $u"
  for M in $MS; do
    HEXRAY_ADAPTIVE_M=$M $hx render $scene --method ${METHOD:-vcm} --width ${SIDE:-256} --height ${SIDE:-256} --time $T --seed $seed -q --adaptive --out /tmp/e_a.exr
    a=$($hx compare /tmp/e_a.exr $ref | awk '/^relMSE/ {print $2}')
    line="$line M$M $(python3 -c "print(f'{$a/$u:.3f}')")"
  done
  echo "$line"
done
