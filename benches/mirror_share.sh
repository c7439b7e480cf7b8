#!/usr/bin/env bash
# How much of a method's noise on tncg15_room comes through its mirror wall: the same room with
# the mirror wall made black (diffuse, albedo 0), each method rendered with --variance, and the
# mean over pixels of the film's variance of the pixel mean over (value² + 0.01), the relMSE's
# denominator (`hexray compare`'s relmse_reference_noise of the render taken as the reference).
# The quotient "with the mirror / without" is the factor the mirror wall multiplies the noise
# by; the seconds give each method's cost, so relative variance x seconds is its inverse
# efficiency.
#
#   [SPP=64] [HEXRAY=target/release/hexray] benches/mirror_share.sh   (256x256, CPU)
#
# SPP: iterations (vcm) or samples (path) per render. HEXRAY is used as built: build it first
# (`cargo build --release`); the header names the checkout it was run from (`git describe`).
#
# The variance of a pixel mean is estimated from its own samples, which understates heavy tails
# (path tracing's rare bright paths): read the path rows as a lower bound.
set -euo pipefail
cd "$(dirname "$0")/.."
hexray=${HEXRAY:-target/release/hexray}
spp=${SPP:-64}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

python3 - "$work/no_mirror_wall.json" <<'PY'
import json, sys
scene = json.load(open("scenes/tncg15_room.json"))
scene["name"] = "tncg15_room_no_mirror_wall"
scene["materials"]["black"] = {"type": "diffuse", "albedo": [0, 0, 0]}
for t in scene["triangles"]:
    if t.get("part") == "wall EF":
        t["material"] = "black"
json.dump(scene, open(sys.argv[1], "w"))
PY

echo "# $(date -u +%Y-%m-%dT%H:%MZ), $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs), $(nproc) cores; hexray $(git describe --always --dirty), $spp spp, 256x256"
echo "scene,method,seconds,relative_variance"
for scene in scenes/tncg15_room.json "$work/no_mirror_wall.json"; do
    name=$(basename "$scene" .json)
    for method in vcm bdpt path; do
        out="$work/${name}_$method.exr"
        seconds=$("$hexray" render "$scene" --backend cpu --method "$method" --spp "$spp" \
            --width 256 --height 256 --seed 1 --variance --out "$out" 2>&1 |
            sed -n 's/^rendered .* in \([0-9.]*\) s.*/\1/p')
        noise=$("$hexray" compare "$out" "$out" --json |
            python3 -c 'import json, sys; print(json.load(sys.stdin)["relmse_reference_noise"])')
        if [ -z "$seconds" ] || [ "$noise" = None ]; then
            echo "mirror_share: no time or no variance from the $method render of $name" >&2
            exit 1
        fi
        echo "$name,$method,$seconds,$noise"
    done
done
