#!/usr/bin/env bash
# What Whitted ray tracing leaves out on the reference scenes: its image against a deep
# path-traced one of the same size, by image mean (the ratio is the share of the light it
# keeps) and relMSE (hexray compare). CPU backend, 128x128; path 2048 spp, Whitted 256.
#
#   docs/records/2026-11-29_whitted/missing_light.sh [HEXRAY]
set -euo pipefail
cd "$(dirname "$0")/../../.."
hexray=${1:-target/release/hexray}
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
for scene in tncg15_room glass_room cornell_box; do
    "$hexray" render "scenes/$scene.json" --backend cpu --method path --width 128 --height 128 \
        --spp 2048 --seed 1 -q --out "$out/${scene}_path.exr"
    "$hexray" render "scenes/$scene.json" --backend cpu --method whitted --width 128 --height 128 \
        --spp 256 --seed 2 -q --out "$out/${scene}_whitted.exr"
    echo "## $scene: whitted (256 spp) against path (2048 spp)"
    "$hexray" compare "$out/${scene}_whitted.exr" "$out/${scene}_path.exr"
done
