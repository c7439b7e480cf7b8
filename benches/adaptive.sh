#!/usr/bin/env bash
# Adaptive sampling against uniform sampling at equal time, path tracing on the CPU,
# and the most that any per-pixel allocation could gain on each scene.
#
#   benches/adaptive.sh [OUT]      (default OUT: docs/records/adaptive)
#
# 1. Equal time: `hexray render --method path --time T` uniform and `--adaptive`, alternating,
#    seeds SEEDS (default "1 2 3"); relMSE by `hexray compare` against
#    - tncg15_room, 256x256, T = 4 s, CPU: tests/data/references/h100/tncg15_room_256.exr;
#    - mirror_caustic (scenes/stability), 128x128, T = 2 s, CPU, and T = 8 s on the GPU adapter
#      (lavapipe here; its time includes the kernel's compilation): a uniform render of 8192 spp
#      (seed 99) that this script makes first (about 20 s).
# 2. The bound (examples/adaptive_bound.rs): from two uniform renders with --variance (seeds 11
#    and 12), the relMSE of the best plan of `--adaptive`'s form over uniform's, at equal
#    samples and without a warm-up: path (1024 spp) and vcm (256 iterations) on tncg15_room,
#    path on mirror_caustic (1024 spp).
# Writes OUT/adaptive.txt. About 3.5 minutes on 2 cores. A benchmark: it asserts nothing.
set -euo pipefail
cd "$(dirname "$0")/.."
hexray=${HEXRAY:-target/release/hexray}
out=${1:-docs/records/adaptive}
seeds=${SEEDS:-1 2 3}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
mkdir -p "$out"
cargo build --release --example adaptive_bound -q
bound=target/release/examples/adaptive_bound
start=$(date +%s)

render() { "$hexray" render "$@" --method path -q; }
relmse() { "$hexray" compare "$1" "$2" | awk '/^relMSE/ {print $2}'; }

{
echo "# benches/adaptive.sh, $(date -u +%Y-%m-%dT%H:%MZ), hexray $(git rev-parse --short HEAD)"
echo "# $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //'), $(nproc) cores"
echo
echo "## Equal time: relMSE, uniform and --adaptive (alternating), and their ratio"
echo "scene backend seconds seed uniform adaptive ratio"
render scenes/stability/mirror_caustic.json --backend cpu --width 128 --height 128 --spp 8192 \
    --seed 99 --out "$tmp/mirror_caustic_ref.exr"
for case in "tncg15_room cpu 256 4 tests/data/references/h100/tncg15_room_256.exr" \
            "stability/mirror_caustic cpu 128 2 $tmp/mirror_caustic_ref.exr" \
            "stability/mirror_caustic gpu 128 8 $tmp/mirror_caustic_ref.exr"; do
    set -- $case
    scene=$1 backend=$2 side=$3 seconds=$4 ref=$5
    for seed in $seeds; do
        render "scenes/$scene.json" --backend "$backend" --width "$side" --height "$side" \
            --time "$seconds" --seed "$seed" --out "$tmp/u.exr"
        render "scenes/$scene.json" --backend "$backend" --width "$side" --height "$side" \
            --time "$seconds" --seed "$seed" --adaptive --out "$tmp/a.exr"
        u=$(relmse "$tmp/u.exr" "$ref")
        a=$(relmse "$tmp/a.exr" "$ref")
        echo "$(basename "$scene") $backend $seconds $seed $u $a $(python3 -c "print(f'{$a / $u:.3f}')")"
    done
done
echo
echo "## The bound: relMSE of the best plan of --adaptive's form over uniform, equal samples"
echo "scene method R F ratio"
for case in "tncg15_room path 256 1024 16 tests/data/references/h100/tncg15_room_256.exr" \
            "tncg15_room vcm 256 256 16 tests/data/references/h100/tncg15_room_256.exr" \
            "stability/mirror_caustic path 128 1024 8 $tmp/mirror_caustic_ref.exr"; do
    set -- $case
    scene=$1 method=$2 side=$3 n=$4 r=$5 ref=$6
    for seed in 11 12; do
        "$hexray" render "scenes/$scene.json" --backend cpu --method "$method" --width "$side" \
            --height "$side" --spp "$n" --seed "$seed" --variance --out "$tmp/b$seed.exr" -q
    done
    for f in 0.25 0.1; do
        for rr in 2 "$r"; do
            echo "$(basename "$scene") $method $rr $f $("$bound" "$ref" "$tmp/b11_var.exr" "$tmp/b12_var.exr" "$rr" "$f")"
        done
    done
done
echo
echo "# $(( $(date +%s) - start )) s"
} | tee "$out/adaptive.txt"
