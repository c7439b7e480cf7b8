#!/usr/bin/env bash
# One device call (2026-11-27): the integration tests on a hardware GPU (first run of the planar-mirror
# kernels there), bench of every method at 256 and 512, every GPU method at equal time at 512x512 and as
# curves at 256x256 against the committed references, and the bidirectional stage times.
set -u
for f in .gl/*.deb; do dpkg -x $f /; done; ldconfig
mkdir -p /work && ln -sfn "$PWD" /work/main
mkdir -p target/release && cp .devbin/hexray target/release/hexray
H=target/release/hexray
step() { echo "== $(date -u +%H:%M:%S) $*"; }
step machine
{ date -u; nproc; grep -m1 'model name' /proc/cpuinfo; nvidia-smi --query-gpu=name,driver_version,memory.total,clocks.max.sm --format=csv; $H info; } > $OUT/machine.txt 2>&1
head -12 $OUT/machine.txt
step tests
timeout 150 .devbin/tests --test-threads 16 > $OUT/tests.txt 2>&1; echo "exit $?" >> $OUT/tests.txt
grep -E "^test result|FAILED|panicked|^exit" $OUT/tests.txt | head -20
mkdir -p /tmp/curves
step "bench 256 cpu,gpu; 512 gpu"
$H bench --backend cpu,gpu --method path,light,bdpt,sppm,vcm --spp 64 --out /tmp/curves/bench_256.json > $OUT/bench.txt 2>&1
$H bench --backend gpu --method path,light,bdpt,sppm,vcm --spp 128 --width 512 --height 512 --out /tmp/curves/bench_512.json >> $OUT/bench.txt 2>&1
grep -E "with |warn" $OUT/bench.txt | head -40
step "stage times"
for size in 256 512; do .devbin/hexray_stages bench scenes/tncg15_room.json --backend gpu --method bdpt,sppm,vcm --spp 16 --width $size --height $size --out /tmp/st.json >> $OUT/stages.txt 2>&1; done
tail -30 $OUT/stages.txt
step "equal time 512x512, 4 s a method, seed 5"
mkdir -p /tmp/r /tmp/curves; echo "scene method | rendered line | relmse" > $OUT/equal_time_512.txt
for s in tncg15_room glass_room; do for m in path bdpt sppm vcm; do
  line=$($H render scenes/$s.json --backend gpu --method $m --time 4 --seed 5 --out /tmp/r/${s}_$m.exr 2>&1 | grep '^rendered')
  rel=$($H compare /tmp/r/${s}_$m.exr tests/data/references/h100/${s}_256.exr --json 2>/dev/null | python3 -c 'import json,sys; print(json.load(sys.stdin)["relmse"])')
  echo "$s $m | $line | $rel" | tee -a $OUT/equal_time_512.txt
done; done
for line in "tncg15_room tests/data/references/h100/tncg15_room_256.exr" "glass_room tests/data/references/h100/glass_room_256.exr" "cornell_box tests/data/references/cornell_box_256.npy"; do
  read -r name ref <<< "$line"
  step "curves $name 256x256, 6 s each"
  $H curve scenes/$name.json --backend gpu --method path,bdpt,sppm,vcm --time 6 --reference $ref --out /tmp/curves/$name 2>&1 | tail -n 6 | tee -a $OUT/curves.txt
done
(cd /tmp && tar czf $OUT/curves.tgz curves)
step done
