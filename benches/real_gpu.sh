#!/usr/bin/env bash
# The GPU backend on a hardware GPU, in one run: the adapter, the integration tests, camera paths/s
# of every method on both backends, and relMSE against time of every method on the GPU against a
# deep GPU path-traced reference rendered in the same run.
#
#   benches/real_gpu.sh [OUTDIR]        # default out/real_gpu; ~7 min on one H100 and 16 cores
#
# Needs only built binaries, no toolchain, so that it runs on a lent machine without cargo:
#   HEXRAY  the renderer (default target/release/hexray)
#   TESTS   the integration-test binary (target/release/deps/tests-*, from
#           `cargo test --release --no-run`); left out when unset
#   STAGES  a build with `--features stage-times` (where a bidirectional iteration's time
#           goes, stage by stage); left out when unset
# CURVES=0 leaves out the references and the curves (about 4 of the 7 minutes);
# FIRST_IMAGE_SIZE (default 800) sizes the first-image step.
# SECONDS_PER_CURVE (default 8), REFERENCE_SECONDS (default 30), BENCH_SPP (default 64, at
# 256x256), BENCH_SPP_512 (default 256, GPU only) and GOAL_SPP (default 50, at 800x800) size
# the run. The tests find the scenes through the path they were built in; where the checkout
# sits elsewhere, link it there first. On a lent machine the binaries travel stripped (`strip -o`)
# with the Vulkan loader; docs/records/2026-11-26_h100/ shows one run and its commands. On a fast
# GPU, bench's short rows (path and light at 64 spp, the 800x800 goal, the stage runs) finish in
# tens of milliseconds and are flagged as too short to time: expected; the curves and the
# 30 s references give the long-run rates.
set -uo pipefail
cd "$(dirname "$0")/.."
hexray=${HEXRAY:-target/release/hexray}
out=${1:-out/real_gpu}
seconds=${SECONDS_PER_CURVE:-8}
reference_seconds=${REFERENCE_SECONDS:-30}
mkdir -p "$out"

step() { echo "== $(date -u +%H:%M:%S) $*"; }

step machine
{
    date -u
    echo "cores: $(nproc)"
    grep -m1 'model name' /proc/cpuinfo
    command -v nvidia-smi > /dev/null &&
        nvidia-smi --query-gpu=name,driver_version,memory.total,clocks.max.sm --format=csv
} > "$out/machine.txt" 2>&1
"$hexray" info > "$out/info.txt" 2>&1
cat "$out/machine.txt" "$out/info.txt"
grep -q '^\[' "$out/info.txt" || { echo "no GPU adapter: stopping" >&2; exit 1; }

if [ -n "${TESTS:-}" ]; then
    step "integration tests ($TESTS)"
    timeout "${TEST_SECONDS:-240}" "$TESTS" --test-threads "$(nproc)" > "$out/tests.log" 2>&1
    echo "exit status $?" >> "$out/tests.log"
    grep -E '^test result|FAILED|panicked|exit status' "$out/tests.log" | head -40
fi

# Camera paths/s (for every method but path a "sample" is an iteration of one light and one
# camera subpath per pixel). The CPU rows use all of this machine's cores.
step "bench 256x256, cpu and gpu"
"$hexray" bench --backend cpu,gpu --method path,light,bdpt,sppm,vcm --spp "${BENCH_SPP:-64}" \
    --out "$out/bench_256.json" > "$out/bench_256.txt" 2>&1
cat "$out/bench_256.txt"
step "bench 512x512, gpu"
"$hexray" bench --backend gpu --method path,light,bdpt,sppm,vcm --spp "${BENCH_SPP_512:-256}" --width 512 --height 512 \
    --out "$out/bench_512.json" > "$out/bench_512.txt" 2>&1
cat "$out/bench_512.txt"

# The first image, as a user runs it: the whole process, cold (the driver's shader cache
# pointed at an empty folder: NVIDIA's and Mesa's; hexray's pipeline cache empty), then with
# hexray's pipeline cache alone (the driver's pointed at another empty folder), then twice warm.
# Each run's log says the adapter's time, the kernel's build, the pipeline cache's bytes, the
# first pass and the rate after it apart.
step "first image: tncg15_room ${FIRST_IMAGE_SIZE:-800}x${FIRST_IMAGE_SIZE:-800}, ${GOAL_SPP:-50} spp, path, cold, pipeline cache alone, warm"
cold_cache=$(mktemp -d)
second_cache=$(mktemp -d)
export HEXRAY_PIPELINE_CACHE
HEXRAY_PIPELINE_CACHE=$(mktemp -d)
for run in cold pipeline_cache warm1 warm2; do
    if [ "$run" = cold ]; then
        cache=(env __GL_SHADER_DISK_CACHE_PATH="$cold_cache" MESA_SHADER_CACHE_DIR="$cold_cache")
    elif [ "$run" = pipeline_cache ]; then
        cache=(env __GL_SHADER_DISK_CACHE_PATH="$second_cache" MESA_SHADER_CACHE_DIR="$second_cache")
    else
        cache=(env)
    fi
    start=$(date +%s%N)
    "${cache[@]}" "$hexray" render scenes/tncg15_room.json --backend gpu --method path \
        --width "${FIRST_IMAGE_SIZE:-800}" --height "${FIRST_IMAGE_SIZE:-800}" \
        --spp "${GOAL_SPP:-50}" --out "$out/first_image_$run.exr" \
        > "$out/first_image_$run.txt" 2>&1
    echo "process milliseconds $((($(date +%s%N) - start) / 1000000))" >> "$out/first_image_$run.txt"
    grep -E 'adapter and device|kernel built|pipeline cache|^rendered|^first pass|process milliseconds' \
        "$out/first_image_$run.txt" | sed "s/^/$run: /"
done
rm -rf "$cold_cache" "$second_cache" "$HEXRAY_PIPELINE_CACHE"
unset HEXRAY_PIPELINE_CACHE

step "the first image's steady state: tncg15_room 800x800, 50 spp, path (after bench's 1-spp warm-up)"
"$hexray" bench scenes/tncg15_room.json --backend gpu --width 800 --height 800 \
    --spp "${GOAL_SPP:-50}" --out "$out/bench_800.json" > "$out/bench_800.txt" 2>&1
cat "$out/bench_800.txt"

if [ -n "${STAGES:-}" ]; then
    for size in 256 512; do
        step "stage times, tncg15_room ${size}x$size"
        "$STAGES" bench scenes/tncg15_room.json --backend gpu --method bdpt,sppm,vcm --spp 16 \
            --width $size --height $size --out "$out/stages_$size.json" 2>&1 |
            tee "$out/stages_$size.txt"
    done
fi

if [ "${CURVES:-1}" = 0 ]; then
    step done
    exit 0
fi

# References: GPU path tracing (unbiased) for REFERENCE_SECONDS, with its variance, so that its
# own noise can be subtracted; cornell_box has the committed Mitsuba reference.
seed=777
: > "$out/references.txt"
for name in tncg15_room glass_room; do
    step "reference $name: gpu path, $reference_seconds s"
    "$hexray" render "scenes/$name.json" --backend gpu --method path --time "$reference_seconds" \
        --width 256 --height 256 --seed $seed --variance --out "$out/refs/${name}_256.exr" 2>&1 |
        grep '^rendered' | tee -a "$out/references.txt"
    seed=$((seed + 1))
done

for line in "tncg15_room $out/refs/tncg15_room_256.exr" "glass_room $out/refs/glass_room_256.exr" \
    "cornell_box tests/data/references/cornell_box_256.npy"; do
    read -r name ref <<< "$line"
    step "curves $name: gpu path, bdpt, sppm, vcm, $seconds s each"
    "$hexray" curve "scenes/$name.json" --backend gpu --method path,bdpt,sppm,vcm \
        --time "$seconds" --reference "$ref" --out "$out/curves/$name" 2>&1 | tail -n 6
    "$hexray" compare "$ref" "$ref" --json > "$out/curves/$name/reference.json"
done
step done
