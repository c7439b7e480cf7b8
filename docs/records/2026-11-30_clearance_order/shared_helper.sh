#!/usr/bin/env bash
# 130ad57 (clr) / the shared nearest-first helper (refac), alternated
cd /work/main
export XDG_RUNTIME_DIR=/tmp/xdg
for r in 1 2 3; do
  if [ $((r % 2)) = 1 ]; then order="clr refac"; else order="refac clr"; fi
  for b in $order; do
    bin=/tmp/ab/${b}_hexray
    $bin bench scenes/tncg15_room.json scenes/perf/bunny_room_1m.json --backend gpu --method path --spp 8 --width 256 --height 256 2>&1 | awk -v r=$r -v b=$b '$2=="gpu" {print r, b, "lavapipe path", $1, $7 " s"}'
    $bin bench scenes/tncg15_room.json scenes/perf/bunny_room_1m.json --backend gpu --method vcm --spp 4 --width 256 --height 256 2>&1 | awk -v r=$r -v b=$b '$2=="gpu" {print r, b, "lavapipe vcm", $1, $7 " s"}'
    $bin bench scenes/tncg15_room.json scenes/perf/bunny_room_1m.json --backend cpu --threads 2 --method vcm --spp 8 --width 256 --height 256 2>&1 | awk -v r=$r -v b=$b '$2=="cpu" {print r, b, "cpu vcm", $1, $7 " s"}'
  done
done
