#!/usr/bin/env bash
# Second device call (2026-11-27): the integration tests with the merge radius's new default
# (0.01 of the scene radius), and every GPU method at equal time with the old default (0.003) and
# the new, at 256x256 (6 s) and 512x512 (4 s), seed 5, one render each.
set -u
for f in .gl/*.deb; do dpkg -x $f /; done; ldconfig
mkdir -p /work && ln -sfn "$PWD" /work/main
mkdir -p target/release && cp .devbin/hexray target/release/hexray
H=target/release/hexray
step() { echo "== $(date -u +%H:%M:%S) $*"; }
step machine
{ date -u; nproc; nvidia-smi --query-gpu=name,driver_version,memory.total,clocks.max.sm --format=csv; $H info; } > $OUT/machine2.txt 2>&1
head -6 $OUT/machine2.txt
step tests
timeout 150 .devbin/tests --test-threads 16 > $OUT/tests2.txt 2>&1; echo "exit $?" >> $OUT/tests2.txt
grep -E "^test result|FAILED|panicked|^exit" $OUT/tests2.txt | head -20
mkdir -p /tmp/r
echo "size scene method radius | rendered line | relmse (reference noise not subtracted)" > $OUT/radius_equal_time.txt
for size in 256 512; do
  t=6; [ $size = 512 ] && t=4
  for s in tncg15_room glass_room cornell_box; do
    case $s in cornell_box) ref=tests/data/references/cornell_box_256.npy; old=1.4411106;; *) ref=tests/data/references/h100/${s}_256.exr; old=0.03354102;; esac
    step "$size $s"
    for mr in "path -" "vcm $old" "vcm default" "sppm $old" "sppm default"; do
      read -r m r <<< "$mr"; extra=""; [ "$r" != "-" ] && [ "$r" != default ] && extra="--radius $r"
      line=$($H render scenes/$s.json --backend gpu --method $m $extra --time $t --seed 5 --width $size --height $size --out /tmp/r/x.exr 2>&1 | grep '^rendered')
      rel=$($H compare /tmp/r/x.exr $ref --json 2>/dev/null | python3 -c 'import json,sys; print(json.load(sys.stdin)["relmse"])')
      echo "$size $s $m $r | $line | $rel" | tee -a $OUT/radius_equal_time.txt
    done
  done
done
step done
