#!/usr/bin/env bash
# One device call (2026-11-28), build f8b4185: the integration tests on a hardware GPU (first run there
# of the emitter choice by selects, shaders/light.wgsl), every method's bench at 256x256 (CPU rows on
# the machine's 16 cores) and the GPU's at 512x512, and every GPU method at equal time (6 s, 256x256,
# seed 5) against the committed references: vcm's and sppm's merge radius since the clearance, on
# hardware for the first time.
set -u
for f in .gl/*.deb; do dpkg -x $f /; done; ldconfig
mkdir -p /work && ln -sfn "$PWD" /work/main
mkdir -p target/release && cp .devbin/hexray target/release/hexray
H=target/release/hexray
step() { echo "== $(date -u +%H:%M:%S) $*"; }
step machine
{ date -u; nproc; grep -m1 'model name' /proc/cpuinfo; nvidia-smi --query-gpu=name,driver_version,memory.total,clocks.max.sm --format=csv; $H info; } > $OUT/machine.txt 2>&1
head -8 $OUT/machine.txt
step tests
timeout 180 .devbin/tests --test-threads 16 > $OUT/tests.txt 2>&1; echo "exit $?" >> $OUT/tests.txt
grep -E "^test result|FAILED|panicked|^exit" $OUT/tests.txt | head -20
step "bench 256 cpu,gpu; 512 gpu"
$H bench --backend cpu,gpu --method path,light,bdpt,sppm,vcm --spp 64 --out $OUT/bench_256.json > $OUT/bench.txt 2>&1
$H bench --backend gpu --method path,light,bdpt,sppm,vcm --spp 128 --width 512 --height 512 --out $OUT/bench_512.json >> $OUT/bench.txt 2>&1
grep -E "with |warn" $OUT/bench.txt | head -50
step "equal time 256x256, 6 s a method, seed 5"
mkdir -p /tmp/r; echo "scene method | rendered line | relmse (reference noise not subtracted)" > $OUT/equal_time_256.txt
for s in tncg15_room glass_room cornell_box; do
  case $s in cornell_box) ref=tests/data/references/cornell_box_256.npy;; *) ref=tests/data/references/h100/${s}_256.exr;; esac
  for m in path bdpt sppm vcm; do
    line=$($H render scenes/$s.json --backend gpu --method $m --time 6 --seed 5 --out /tmp/r/${s}_$m.exr 2>&1 | grep '^rendered')
    rel=$($H compare /tmp/r/${s}_$m.exr $ref --json 2>/dev/null | python3 -c 'import json,sys; print(json.load(sys.stdin)["relmse"])')
    echo "$s $m | $line | $rel" | tee -a $OUT/equal_time_256.txt
  done
done
step done
