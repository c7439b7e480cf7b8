#!/usr/bin/env bash
# Second device call (2026-11-28), build f8b4185: the renders behind the two same-streams tests that
# failed in the first call (vcm on tncg15_room and glass_room, 64x64, 16 iterations, seed 7, the
# tests' streams), with vcm-full and sppm beside them, as EXR files to compare pixel by pixel with the
# CPU's renders of the same streams on another machine.
set -u
for f in .gl/*.deb; do dpkg -x $f /; done; ldconfig
H=.devbin/hexray
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader
mkdir -p $OUT/same_streams
for s in tncg15_room glass_room; do for m in vcm vcm-full sppm; do
  $H render scenes/$s.json --backend gpu --method $m --seed 7 --width 64 --height 64 --spp 16 --out $OUT/same_streams/${s}_$m.exr 2>&1 | grep -E '^rendered'
  rm -f $OUT/same_streams/${s}_$m.film $OUT/same_streams/${s}_$m.png
done; done
ls $OUT/same_streams
