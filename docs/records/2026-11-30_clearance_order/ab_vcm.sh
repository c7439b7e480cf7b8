#!/usr/bin/env bash
# base (1da3cc0) / new (nearest-first clearance) alternated: vcm on the CPU and lavapipe
cd /work/main
export XDG_RUNTIME_DIR=/tmp/xdg
out=/tmp/ab/clr; mkdir -p $out
for r in 1 2 3; do
  if [ $((r % 2)) = 1 ]; then order="base new"; else order="new base"; fi
  for b in $order; do
    bin=/tmp/ab/base_hexray; [ $b = new ] && bin=/tmp/ab/clr_hexray
    $bin bench scenes/tncg15_room.json scenes/bunny_room.json scenes/perf/bunny_room_1m.json --backend cpu --threads 2 --method vcm --spp 8 --width 256 --height 256 --out $out/${b}_cpu_$r.json 2>&1 | awk -v r=$r -v b=$b '$2=="cpu" {print r, b, "cpu vcm", $1, $8, $7 " s"}'
    $bin bench scenes/tncg15_room.json scenes/perf/bunny_room_1m.json --backend gpu --method vcm --spp 4 --width 256 --height 256 --out $out/${b}_gpu_$r.json 2>&1 | awk -v r=$r -v b=$b '$2=="gpu" {print r, b, "lavapipe vcm", $1, $8, $7 " s"}'
  done
done
