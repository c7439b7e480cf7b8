#!/usr/bin/env bash
# issue 7's goal from a cold start: the first dispatch's size (65 536 paths, old) against 2^23 on a discrete GPU (new)
set -u
for f in .gl/*.deb; do dpkg -x $f / 2>/dev/null; done; ldconfig
for r in 1 2 3; do for b in old new; do X=.devbin/hexray; [ $b = old ] && X=.devbin/hexray_old
  echo "$b $r: $($X render scenes/tncg15_room.json --backend gpu --method path --width 800 --height 800 --spp 50 --out /tmp/r_$b.exr 2>&1 | grep '^rendered')"
  echo "$b $r bench: $($X bench scenes/tncg15_room.json --backend gpu --width 800 --height 800 --spp 50 --out $OUT/bench800_${b}_run$r.json 2>&1 | grep 'with path' | sed 's/.*: //')"
done; done
for m in vcm sppm; do for b in old new; do X=.devbin/hexray; [ $b = old ] && X=.devbin/hexray_old
  echo "$b $m: $($X render scenes/tncg15_room.json --backend gpu --method $m --spp 8 --out /tmp/r_$b.exr 2>&1 | grep '^rendered')"; done; done
