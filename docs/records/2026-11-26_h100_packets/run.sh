#!/usr/bin/env bash
# One device call: the tests, GPU methods at 512x512 and equal time, issue 7's goal, CPU packets on 16 cores.
set -u
for f in .gl/*.deb; do dpkg -x $f /; done; ldconfig
mkdir -p /work && ln -sfn "$PWD" /work/main
H=.devbin/hexray; B=.devbin/hexray_before
step() { echo "== $(date -u +%H:%M:%S) $*"; }
step machine; nproc; nvidia-smi --query-gpu=name,driver_version --format=csv,noheader; $H info 2>&1 | head -3
step tests
timeout 150 .devbin/tests --test-threads 16 > $OUT/tests.txt 2>&1; echo "exit $?" >> $OUT/tests.txt
grep -E "^test result|FAILED|panicked|^exit" $OUT/tests.txt | head -20
step "equal time 512x512, 4 s a method, seed 5"
mkdir -p $OUT/r; echo "scene method spp seconds relmse" > $OUT/equal_time_512.txt
for s in tncg15_room glass_room; do for m in path bdpt sppm vcm; do
  line=$($H render scenes/$s.json --backend gpu --method $m --time 4 --seed 5 --out $OUT/r/${s}_$m.exr 2>&1 | grep '^rendered')
  rel=$($H compare $OUT/r/${s}_$m.exr tests/data/references/h100/${s}_256.exr --json 2>/dev/null | python3 -c 'import json,sys; print(json.load(sys.stdin)["relmse"])')
  echo "$s $m | $line | $rel" | tee -a $OUT/equal_time_512.txt
done; done
rm -rf $OUT/r
step "issue 7 goal: tncg15_room 800x800 path, 50 spp, and 2000 spp"
for spp in 50 2000; do $H bench scenes/tncg15_room.json --backend gpu --width 800 --height 800 --spp $spp --out $OUT/bench_800_$spp.json 2>&1 | grep -E "with path|warning" ; done
step "CPU path, 16 threads, before/after packets, alternated 3x"
for r in 1 2 3; do for b in before after; do X=$H; [ $b = before ] && X=$B
  $X bench --backend cpu --method path --spp 64 --threads 16 --out $OUT/cpu16_${b}_run$r.json 2>&1 | grep "with path" | sed "s/^/$b $r: /"; done; done
step done
