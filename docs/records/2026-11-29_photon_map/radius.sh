#!/usr/bin/env bash
# photon-map radius share: relMSE at equal time (CPU, 256x256, 20 s) against the deep references.
set -euo pipefail
cd "$(dirname "$0")/../../.."
export XDG_RUNTIME_DIR=/tmp
bin=${HEXRAY:-target/release/hexray}
out=out/photon_map_radius; mkdir -p $out
for scene in tncg15_room glass_room cornell_box; do
  case $scene in cornell_box) ref=tests/data/references/cornell_box_256.npy;; *) ref=out/methods/refs/${scene}_256.exr;; esac
  r0=$($bin render scenes/$scene.json --backend cpu --method photon-map --width 256 --height 256 --spp 1 --out $out/probe.exr 2>&1 | awk '/^merge_radius/{print $2}')
  for f in 0.5 1 2 4; do
    r=$(python3 -c "print($r0*$f)")
    for seed in 21 22; do
      $bin render scenes/$scene.json --backend cpu --method photon-map --width 256 --height 256 --time 20 --seed $seed --radius $r --out $out/$scene-$f-$seed.exr --quiet 2>/dev/null || true
      e=$($bin compare $out/$scene-$f-$seed.exr $ref 2>&1 | awk '/^relMSE/{print $2}')

      echo "$scene k_factor=$f r=$r seed=$seed relMSE=$e"
    done
  done
done
