#!/usr/bin/env bash
# Whether two builds render the same images: path, light, bdpt, sppm and vcm on the three
# reference scenes with the CPU backend, 96x96, seed 3 (16 spp for path, 4 iterations for the
# others), compared by `hexray compare`; RMSE 0 means every pixel is the same.
#
#   benches/same_images.sh OLD_BINARY NEW_BINARY OUT_DIR
set -euo pipefail
old=$1; new=$2; out=$3
cd "$(dirname "$0")/.."
mkdir -p "$out"
for scene in tncg15_room cornell_box glass_room; do
    for method in path light bdpt sppm vcm; do
        spp=4; [ "$method" = path ] && spp=16
        for b in old new; do
            bin=$old; [ "$b" = new ] && bin=$new
            "$bin" render "scenes/$scene.json" --backend cpu --method "$method" --width 96 \
                --height 96 --spp "$spp" --seed 3 --threads 2 --quiet \
                --out "$out/${scene}_${method}_$b.exr"
        done
        echo "$scene $method $("$new" compare "$out/${scene}_${method}_new.exr" \
            "$out/${scene}_${method}_old.exr" | grep '^RMSE')"
    done
done
