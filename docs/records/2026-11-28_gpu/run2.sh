#!/usr/bin/env bash
# The next device call (written 2026-11-28, refused then: no machine lent; to run on the next GPU
# lent, from binaries of the build to check in .devbin): the integration tests, whose vcm
# same-streams checks now run at 0.01 of the scene radius, and the renders behind those checks
# (64x64, 16 iterations, seed 7, the tests' streams) at 0.01 and at vcm's default 0.03 (given
# explicitly: `hexray render` on a hardware GPU defaults to 0.003), with vcm-full and sppm
# beside them, as EXR files to compare pixel by pixel with the CPU's renders of the same streams
# on another machine (the count of tests/photon_merging.rs's `pixels_differing`).
set -u
for f in .gl/*.deb; do dpkg -x $f /; done; ldconfig
mkdir -p /work && ln -sfn "$PWD" /work/main
mkdir -p target/release && cp .devbin/hexray target/release/hexray
H=target/release/hexray
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader
timeout 180 .devbin/tests --test-threads 16 > $OUT/tests2.txt 2>&1; echo "exit $?" >> $OUT/tests2.txt
grep -E "^test result|FAILED|panicked|same seed|^exit" $OUT/tests2.txt | head -30
mkdir -p $OUT/same_streams
# tncg15_room and glass_room share the scene radius 11.18034 (r1 = 0.1118034 at 0.01, 0.3354102 at 0.03)
for s in tncg15_room glass_room; do for m in vcm vcm-full sppm; do for r in 0.1118034 0.3354102; do
  $H render scenes/$s.json --backend gpu --method $m --radius $r --seed 7 --width 64 --height 64 --spp 16 --out $OUT/same_streams/${s}_${m}_$r.exr 2>&1 | grep -E '^rendered'
  rm -f $OUT/same_streams/${s}_${m}_$r.film $OUT/same_streams/${s}_${m}_$r.png
done; done; done
ls $OUT/same_streams | wc -l
