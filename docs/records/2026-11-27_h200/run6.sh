#!/usr/bin/env bash
# Sixth device call (2026-11-27, build cdd2a5f's renderer): vcm at 256x256 for 6 s
# with the merge radius at 0.003 and 0.01 (the default) of the scene radius, seed 5.
set -u
for f in .gl/*.deb; do dpkg -x $f /; done; ldconfig
H=.devbin/hexray
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader
mkdir -p /tmp/r
echo "size scene method factor | rendered line | relmse (reference noise not subtracted)" > $OUT/first_diffuse_radius_256.txt
for s in tncg15_room glass_room cornell_box; do
  case $s in cornell_box) ref=tests/data/references/cornell_box_256.npy; R=480.3702;; *) ref=tests/data/references/h100/${s}_256.exr; R=11.18034;; esac
  for m in vcm; do for f in 0.003 0.01; do
    r=$(python3 -c "print($R*$f)")
    line=$($H render scenes/$s.json --backend gpu --method $m --radius $r --time 6 --seed 5 --width 256 --height 256 --out /tmp/r/x.exr 2>&1 | grep '^rendered')
    rel=$($H compare /tmp/r/x.exr $ref --json 2>/dev/null | python3 -c 'import json,sys; print(json.load(sys.stdin)["relmse"])')
    echo "256 $s $m $f | $line | $rel" | tee -a $OUT/first_diffuse_radius_256.txt
  done; done
done
