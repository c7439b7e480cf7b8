#!/usr/bin/env bash
# The one call to make on a lent GPU, from binaries and data prepared here by
# benches/lent_gpu_prepare.sh; it builds nothing. In one run:
#   1. benches/real_gpu.sh without its curves: the adapter, the integration tests, `hexray bench`
#      of every method on both backends at 256x256 and on the GPU at 512x512, the first image
#      (800x800, 50 spp) cold and warm, its steady-state bench, and the bidirectional stage times;
#   2. hexray's path tracer beside Mitsuba 3's cuda_ad_rgb on the same GPU, alternating, ROUNDS
#      rounds: camera paths/s on the three reference scenes at 256x256 and 512x512, and the
#      800x800 50-spp render (Mitsuba: ../shared/mitsuba/gpu/mi_gpu_bench.py; hexray: `hexray
#      bench --backend gpu --method path`), then the ratio per scene and size, median and range.
# Everything lands in one archive, $OUT/lent_gpu.tgz (a lent machine sends back at most eight
# files), with the summary also in $OUT/summary.txt.
#
#   run(command="bash benches/lent_gpu.sh", carry=[".gl", ".devbin"], timeout_s=590)
#
# About 7 minutes on an H200 with 16 cores (estimated); the side by side
# skips its later rounds past 7 minutes.
#
# Environment: ROUNDS (default 2), SPP_256 (default 2048) and SPP_512 (default 512), hexray's
# samples per pixel at each size (about a second each at path tracing's rate on an H100), and
# DRY_RUN=1 to try the side by side without a GPU: lavapipe against Mitsuba's llvm_ad_rgb at
# 64x64, without step 1; MITSUBA_PYTHON, a Python with Mitsuba installed, replaces the trimmed
# copy (which is built for the lent machine's CPython 3.12).
set -uo pipefail
cd "$(dirname "$0")/.."
out=${OUT:-out/lent_gpu}
work=$(mktemp -d)
mkdir -p "$out"
rounds=${ROUNDS:-2}
step() { echo "== $(date -u +%H:%M:%S) $*"; }

# The Vulkan loader (the machine has the driver but not the loader), and the checkout where the
# tests were built (they find the scenes through that path).
if ! ldconfig -p | grep -q libvulkan.so.1; then
    for f in .gl/*.deb; do dpkg -x "$f" /; done
    ldconfig
fi
if [ ! -e /work/main ]; then
    mkdir -p /work && ln -sfn "$PWD" /work/main
fi
bin=$(mktemp -d)
tar -C "$bin" -xJf .devbin/bin.tar.xz
mkdir -p target/release
cp "$bin/hexray" target/release/hexray
hexray=target/release/hexray
if ! "$hexray" info 2>/dev/null | grep -q '^\['; then
    export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
fi

if [ "${DRY_RUN:-0}" = 1 ]; then
    sizes=(64)
else
    step "real_gpu.sh (no curves)"
    sizes=(256 512)
    TESTS="$bin/tests" STAGES="$bin/hexray-stages" CURVES=0 TEST_SECONDS=150 \
        benches/real_gpu.sh "$work/real_gpu" > "$work/real_gpu.log" 2>&1
    grep -E '^==|^test result|FAILED|^tncg15|^cornell|^glass|first pass|^rendered' "$work/real_gpu.log" | head -80
fi

# Mitsuba 3 from the trimmed copy (../shared/mitsuba/gpu/device_mitsuba.sh's set-up): Dr.Jit is
# pointed at the driver's CUDA and OptiX libraries by name.
step "Mitsuba set-up"
mi=$(mktemp -d)
python=${MITSUBA_PYTHON:-python3}
[ -n "${MITSUBA_PYTHON:-}" ] || tar -C "$mi" -xJf .devbin/mi/mi_trim.tar.xz
find_lib() { ldconfig -p | awk -v n="$1" '$1==n {print $NF; exit}'; }
cuda=$(find_lib libcuda.so.1)
[ -n "$cuda" ] || cuda=$(find /usr/local/nvidia /usr/lib* -name 'libcuda.so.1' 2>/dev/null | head -1)
optix=$(find_lib libnvoptix.so.1)
[ -n "$optix" ] || optix=$(find /usr/local/nvidia /usr/lib* -name 'libnvoptix.so.1' 2>/dev/null | head -1)
echo "libcuda: ${cuda:-missing}; libnvoptix: ${optix:-missing: the driver lacks its graphics capability}" |
    tee "$work/mitsuba_libs.txt"
export DRJIT_LIBCUDA_PATH="$cuda" DRJIT_LIBOPTIX_PATH="$optix" PYTHONPATH="$mi:.devbin/mi"
export DRJIT_CACHE_DIR="$mi/drjit_cache" PYTHONUNBUFFERED=1
if [ "${DRY_RUN:-0}" = 1 ]; then
    export MI_VARIANT=llvm_ad_rgb MI_SMALL=1
fi

# One round: hexray's rows (scene, size, M camera paths/s, and the 800x800 render's seconds) and
# Mitsuba's JSON, in the order given.
run_hexray() { # ROUND
    local r=$1
    for size in "${sizes[@]}"; do
        local spp=${SPP_512:-512}
        [ "$size" = "${sizes[0]}" ] && spp=${SPP_256:-2048}
        [ "${DRY_RUN:-0}" = 1 ] && spp=4
        "$hexray" bench --backend gpu --method path --spp "$spp" --width "$size" --height "$size" \
            --out "$work/hexray_${r}_$size.json" > "$work/hexray_${r}_$size.txt" 2>&1
    done
    local goal=800
    [ "${DRY_RUN:-0}" = 1 ] && goal=64
    "$hexray" render scenes/tncg15_room.json --backend gpu --method path --width $goal \
        --height $goal --spp 50 --out "$work/hexray_goal_$r.exr" > "$work/hexray_goal_$r.txt" 2>&1
}
run_mitsuba() { # ROUND
    timeout 150 "$python" .devbin/mi/mi_gpu_bench.py scenes "$work/mitsuba_$1.json" \
        > "$work/mitsuba_$1.txt" 2>&1 || echo "mitsuba round $1: exit $?" | tee -a "$work/mitsuba_$1.txt"
}
for r in $(seq 1 "$rounds"); do
    # The call has 10 minutes: a round takes about 1.5 (Mitsuba's first with its compiles).
    if [ "$SECONDS" -gt 420 ]; then
        step "side by side: no time left for round $r"
        break
    fi
    step "side by side, round $r"
    if [ $((r % 2)) = 1 ]; then
        run_hexray "$r"
        run_mitsuba "$r"
    else
        run_mitsuba "$r"
        run_hexray "$r"
    fi
done

step "summary"
python3 - "$work" "$rounds" > "$work/summary.txt" <<'PY'
import glob, json, os, re, statistics, sys
work, rounds = sys.argv[1], int(sys.argv[2])
ratios = {}
for r in range(1, rounds + 1):
    try:
        mi = json.load(open(f"{work}/mitsuba_{r}.json"))
    except (OSError, ValueError) as e:
        print(f"round {r}: no Mitsuba figures ({e})")
        continue
    mi_rate = {(row["scene"], row["res"]): row["Mpaths_per_s"] for row in mi["runs"]}
    for path in glob.glob(f"{work}/hexray_{r}_*.json"):
        for row in json.load(open(path))["rows"]:
            key = (row["scene"], row["width"])
            if key in mi_rate:
                h = row["camera_paths_per_second"] / 1e6
                ratios.setdefault(key, []).append((h, mi_rate[key]))
    goal = open(f"{work}/hexray_goal_{r}.txt").read()
    m = re.search(r"rendered 50 spp with path in ([0-9.]+) s", goal)
    f = re.search(r"first pass 1 spp in ([0-9.]+) s", goal)
    size = re.search(r" at ([0-9]+x[0-9]+) on ", goal)
    print(f"round {r}: {size and size.group(1)} 50 spp, hexray render {m and m.group(1)} s (first pass "
          f"{f and f.group(1)} s); Mitsuba first {mi.get('issue7_first')}, second "
          f"{mi.get('issue7_second')}")
print("scene,size,hexray M paths/s,Mitsuba M paths/s,ratio median,min,max,rounds")
for (scene, size), v in sorted(ratios.items()):
    q = [h / m for h, m in v]
    print(f"{scene},{size},{statistics.median(h for h, _ in v):.1f},"
          f"{statistics.median(m for _, m in v):.1f},{statistics.median(q):.2f},{min(q):.2f},"
          f"{max(q):.2f},{len(q)}")
PY
cat "$work/summary.txt"
cp "$work/summary.txt" "$out/summary.txt"
# Images and films stay behind: a file that comes back may hold at most 16 MiB.
find "$work" \( -name '*.film' -o -name '*.exr' -o -name '*.png' \) -delete
tar -C "$work" -czf "$out/lent_gpu.tgz" . 2>/dev/null
ls -l "$out"
step done
