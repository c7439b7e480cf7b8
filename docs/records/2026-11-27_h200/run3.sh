#!/usr/bin/env bash
# Third device call (2026-11-27): vcm and sppm at 512x512 with the merge radius at 0.003 and
# 0.005 of the scene radius (0.005 is 0.01 scaled by 1 / sqrt(N) from 256x256), 4 s, seed 5.
set -u
for f in .gl/*.deb; do dpkg -x $f /; done; ldconfig
H=.devbin/hexray
step() { echo "== $(date -u +%H:%M:%S) $*"; }
step machine; nvidia-smi --query-gpu=name,driver_version --format=csv,noheader
mkdir -p /tmp/r
echo "size scene method factor seed | rendered line | relmse (reference noise not subtracted)" > $OUT/radius_512.txt
for s in tncg15_room glass_room cornell_box; do
  case $s in cornell_box) ref=tests/data/references/cornell_box_256.npy; R=480.3702;; *) ref=tests/data/references/h100/${s}_256.exr; R=11.18034;; esac
  for seed in 5; do for m in vcm sppm; do for f in 0.003 0.005; do
    r=$(python3 -c "print($R*$f)")
    line=$($H render scenes/$s.json --backend gpu --method $m --radius $r --time 4 --seed $seed --width 512 --height 512 --out /tmp/r/x.exr 2>&1 | grep '^rendered')
    rel=$($H compare /tmp/r/x.exr $ref --json 2>/dev/null | python3 -c 'import json,sys; print(json.load(sys.stdin)["relmse"])')
    echo "512 $s $m $f $seed | $line | $rel" | tee -a $OUT/radius_512.txt
  done; done; done
done
step done
