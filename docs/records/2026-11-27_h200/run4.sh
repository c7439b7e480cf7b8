#!/usr/bin/env bash
# Fourth device call (2026-11-27, build cdd2a5f): vcm that ends its camera subpaths at their first
# diffuse vertex. The integration tests on the GPU, then path, vcm, vcm-full and sppm at equal time
# (256x256 for 6 s and 512x512 for 4 s, seed 5) against the committed references.
set -u
for f in .gl/*.deb; do dpkg -x $f /; done; ldconfig
mkdir -p /work && ln -sfn "$PWD" /work/main
mkdir -p target/release && cp .devbin/hexray target/release/hexray
H=target/release/hexray
step() { echo "== $(date -u +%H:%M:%S) $*"; }
step machine
{ date -u; nproc; grep -m1 'model name' /proc/cpuinfo; nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv; } > $OUT/machine.txt 2>&1
cat $OUT/machine.txt
step tests
timeout 150 .devbin/tests --test-threads 16 > $OUT/tests.txt 2>&1; echo "exit $?" >> $OUT/tests.txt
grep -E "^test result|FAILED|panicked|^exit" $OUT/tests.txt | head -20
mkdir -p /tmp/r
echo "size scene method | rendered line | relmse (reference noise not subtracted)" > $OUT/first_diffuse_equal_time.txt
for size in 256 512; do
  t=6; [ $size = 512 ] && t=4
  step "equal time $size, $t s"
  for s in tncg15_room glass_room cornell_box; do
    case $s in cornell_box) ref=tests/data/references/cornell_box_256.npy;; *) ref=tests/data/references/h100/${s}_256.exr;; esac
    for m in path vcm vcm-full sppm; do
      line=$($H render scenes/$s.json --backend gpu --method $m --time $t --seed 5 --width $size --height $size --out /tmp/r/x.exr 2>&1 | grep '^rendered')
      rel=$($H compare /tmp/r/x.exr $ref --json 2>/dev/null | python3 -c 'import json,sys; print(json.load(sys.stdin)["relmse"])')
      echo "$size $s $m | $line | $rel" | tee -a $OUT/first_diffuse_equal_time.txt
    done
  done
done
step done
