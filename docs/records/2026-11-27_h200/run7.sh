#!/usr/bin/env bash
# Seventh device call (2026-11-27): the hardware GPU's default merge radius (0.003 of the scene
# radius) as `hexray render` and `hexray bench` take it without --radius; vcm, 512x512, 4 s, seed 5.
set -u
for f in .gl/*.deb; do dpkg -x $f /; done; ldconfig
H=.devbin/hexray
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader
mkdir -p /tmp/r
for s in tncg15_room glass_room; do
  $H render scenes/$s.json --backend gpu --method vcm --time 4 --seed 5 --out /tmp/r/$s.exr 2>&1 | grep -E '^rendered|radius' | tee -a $OUT/hardware_default_radius.txt
  $H compare /tmp/r/$s.exr tests/data/references/h100/${s}_256.exr --json 2>/dev/null | python3 -c 'import json,sys; print("relmse", json.load(sys.stdin)["relmse"])' | tee -a $OUT/hardware_default_radius.txt
done
python3 - <<'PY' | tee -a $OUT/hardware_default_radius.txt
import struct, json
for s in ("tncg15_room",):
    b = open(f"/tmp/r/{s}.film", "rb").read()
    n = struct.unpack("<I", b[12:16])[0]
    print("film header:", json.loads(b[16:16 + n]))
PY
$H bench scenes/tncg15_room.json --backend gpu --method vcm --spp 64 --out /tmp/r/b.json 2>&1 | tail -3
