#!/usr/bin/env bash
# Seconds per iteration (or per sample, for path) against the image size: whether a method's
# cost grows as the pixel count does. Each size renders a fixed number of samples; the time is
# the render's own (`rendered N spp ... in T s`, after the set-up), divided by N, and the last
# column is that over the pixel count in microseconds (flat where the cost is linear).
#
#   benches/iteration_scaling.sh                        # lavapipe (gpu), vcm, 512^2 .. 4K
#   BACKEND=cpu METHOD=path SIZES="512x512 1024x1024" benches/iteration_scaling.sh
#
# HEXRAY (target/release/hexray), BACKEND (gpu), METHOD (vcm), SCENE (scenes/cornell_box.json),
# SIZES ("512x512 1024x1024 2048x2048 3840x2160"), SPP (samples at the smallest size, 4; fewer
# as the size grows, at least 1), LIMIT (seconds a size may take before it is stopped and
# reported as more than that, 900).
set -euo pipefail
cd "$(dirname "$0")/.."
hexray=${HEXRAY:-target/release/hexray}
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
echo "backend method size spp seconds seconds_per_sample us_per_pixel_sample"
spp=${SPP:-4}
for s in ${SIZES:-512x512 1024x1024 2048x2048 3840x2160}; do
    w=${s%x*}
    h=${s#*x}
    set +e
    timeout -s INT "${LIMIT:-900}" "$hexray" render "${SCENE:-scenes/cornell_box.json}" \
        --backend "${BACKEND:-gpu}" --method "${METHOD:-vcm}" --width "$w" --height "$h" \
        --spp "$spp" --out "$out/i.exr" 2> "$out/log"
    set -e
    line=$(grep '^rendered ' "$out/log" || true)
    n=$(sed -n 's/^rendered \([0-9]*\) spp.*/\1/p' <<< "$line")
    t=$(sed -n 's/.* in \([0-9.]*\) s.*/\1/p' <<< "$line")
    if [ -z "$n" ] || [ "$n" = 0 ]; then
        echo "${BACKEND:-gpu} ${METHOD:-vcm} $s $spp >${LIMIT:-900} - -"
    else
        python3 -c "n, t, p = $n, $t, $w * $h; print(f'${BACKEND:-gpu} ${METHOD:-vcm} $s {n} {t:.2f} {t / n:.3f} {1e6 * t / n / p:.3f}')"
    fi
    spp=$(( spp > 1 ? spp / 2 : 1 ))
done
