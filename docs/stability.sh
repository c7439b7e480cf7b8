#!/usr/bin/env bash
# Regenerates docs/stability.md: for each stability scene (scenes/stability/), a CPU and a GPU
# picture side by side, the property its test states with both backends' measured values (the
# tests' own output), and the relMSE-against-time curve of both backends.
#
#   docs/stability.sh references   # the long CPU references (tests/data/references/stability/;
#                                  # about an hour on 2 cores: the 10^4 tiny light dominates)
#   docs/stability.sh report       # pictures, curves, test values -> docs/stability.md (~25 min)
#   docs/stability.sh markdown     # docs/stability.md again from what `report` left in docs/stability/
#
# HEXRAY (default target/release/hexray) is the binary; build it first with
# `cargo build --release`. The GPU backend runs on whatever adapter wgpu finds (lavapipe here).
set -euo pipefail
cd "$(dirname "$0")/.."
hexray=${HEXRAY:-target/release/hexray}
refs=tests/data/references/stability
out=docs/stability
# Every curve and reference is 32x32 pixels (the tests' size); pictures are 128x128.
size=32
# Seeds: references 1000000 (apart from every test's and picture's seed).
ref_seed=1000000

# name, scene file, reference spp
reference_list() {
    cat <<'EOF'
caustic scenes/stability/caustic.json 65536
tiny_light_1e2 scenes/stability/tiny_light_1e2.json 65536
tiny_light_1e0 scenes/tncg15_room.json 65536
glass_room scenes/glass_room.json 65536
tiny_light_1e4 scenes/stability/tiny_light_1e4.json 262144
grazing scenes/stability/grazing.json 16384
mirror_corridor scenes/stability/mirror_corridor.json 16384
thin_slab scenes/stability/thin_slab.json 16384
EOF
}

references() {
    mkdir -p "$refs"
    reference_list | while read -r name scene spp; do
        echo "== $name: $spp spp"
        "$hexray" reference "$scene" --backend cpu --width $size --height $size --spp "$spp" \
            --seed $ref_seed --out "$refs/${name}_32.exr" --quiet
    done
}

# The value of a curve at a time budget: the relMSE of the last wave finished within it.
relmse_at() {
    python3 - "$1" "$2" "$3" <<'PY'
import csv, sys
path, backend, budget = sys.argv[1], "hexray " + sys.argv[2], float(sys.argv[3])
rows = [r for r in csv.DictReader(open(path)) if r["backend"] == backend and float(r["seconds"]) <= budget]
if rows:
    r = rows[-1]
    print(f"{float(r['relmse']):.3g} ({r['spp']} spp, {float(r['seconds']):.1f} s)")
else:
    print("-")
PY
}

# name, scene, reference (for the curve; "-" for none), what the picture shows
report_list() {
    cat <<'EOF'
caustic scenes/stability/caustic.json caustic_32.exr
tiny_light_1e0 scenes/tncg15_room.json tiny_light_1e0_32.exr
tiny_light_1e2 scenes/stability/tiny_light_1e2.json tiny_light_1e2_32.exr
tiny_light_1e4 scenes/stability/tiny_light_1e4.json tiny_light_1e4_32.exr
grazing scenes/stability/grazing.json grazing_32.exr
far_from_origin_1e3 scenes/stability/tncg15_translated_1e3.json tiny_light_1e0_32.exr
far_from_origin_1e4 scenes/stability/tncg15_translated_1e4.json tiny_light_1e0_32.exr
far_from_origin_1e5 scenes/stability/tncg15_translated_1e5.json tiny_light_1e0_32.exr
far_from_origin_1e6 scenes/stability/tncg15_translated_1e6.json tiny_light_1e0_32.exr
mirror_corridor scenes/stability/mirror_corridor.json mirror_corridor_32.exr
thin_slab scenes/stability/thin_slab.json thin_slab_32.exr
thin_box scenes/stability/thin_box.json -
mirror_doubled scenes/stability/tncg15_mirror_doubled.json -
shadow_colour scenes/stability/tncg15_umbra_view.json -
EOF
}

report() {
    mkdir -p "$out"
    # The tests' measured values, one module at a time, in test order.
    cargo test --release --test tests stability_ -- --nocapture --test-threads 1 \
        > "$out/tests.log" 2>&1 || true
    report_list | while read -r name scene ref; do
        echo "== $name"
        mkdir -p "$out/$name"
        for b in cpu gpu; do
            "$hexray" render "$scene" --backend $b --width 128 --height 128 --spp 64 --seed 3 \
                --out "$out/$name/$b.exr" --quiet
            rm -f "$out/$name/$b.exr"
        done
        if [ "$ref" != "-" ]; then
            "$hexray" curve "$scene" --backend cpu,gpu --reference "$refs/$ref" --time 10 \
                --out "$out/$name" >/dev/null
            rm -f "$out/$name"/*.svg
        fi
    done
    markdown
}

# docs/stability.md from what `report` left in docs/stability/.
markdown() {
    local adapter
    adapter=$("$hexray" info 2>/dev/null | sed -n 's/^\[0\] //p' | head -1)
    {
        echo "# Stability where methods fail"
        echo
        echo "Regenerate with \`docs/stability.sh report\` (references: \`docs/stability.sh references\`)."
        echo "Measured $(date -u +%Y-%m-%d) on $(nproc) cores ($(sed -n 's/^model name\s*: //p' /proc/cpuinfo | head -1)); GPU backend on ${adapter:-no adapter}."
        echo "Pictures: 128x128, 64 spp per backend (seed 3). Curves: ${size}x${size} against a long CPU reference"
        echo "(\`$refs/\`), 10 s per backend; \"relMSE at 10 s\" is the last doubling wave finished within 10 s."
        echo "Each section quotes the lines its test prints (\`$out/tests.log\`): the property, the values and"
        echo "standard errors on each backend, and the planted errors it rejects. The properties themselves"
        echo "are stated in the headers of \`tests/stability_*.rs\`."
        echo
        echo "| scene | relMSE at 10 s, CPU | relMSE at 10 s, GPU |"
        echo "| --- | --- | --- |"
        report_list | while read -r name scene ref; do
            if [ "$ref" != "-" ]; then
                echo "| $name | $(relmse_at "$out/$name/curve.csv" cpu 10) | $(relmse_at "$out/$name/curve.csv" gpu 10) |"
            else
                echo "| $name | (no curve: see the test) | |"
            fi
        done
        echo
        report_list | while read -r name scene ref; do
            echo "## $name"
            echo
            echo "\`$scene\`"
            echo
            echo "| CPU | GPU |"
            echo "| --- | --- |"
            echo "| ![cpu]($name/cpu.png) | ![gpu]($name/gpu.png) |"
            echo
            if [ "$ref" != "-" ]; then
                echo "![relMSE against time]($name/relmse_vs_seconds.png)"
                echo
            fi
        done
        echo "## Tiny lights: the error to expect at 64 spp"
        echo
        echo "One render's relMSE is a poor summary where the error comes from rare, huge samples: most"
        echo "64-spp renders of the 10^4 light never see it at all (their relMSE is small) and a few see"
        echo "it in one sample (theirs is enormous). The expected relMSE at N spp is the reference's"
        echo "per-pixel sample variance over N: mean over pixel-channels of var_r · N_ref / N / (r² + 0.01)"
        echo "(\`hexray compare\` reports var_r / (r² + 0.01) as the reference's own noise). Mitsuba's mean"
        echo "relMSE at 64 spp for the same three sizes: 0.16, 18 and 3500 (at its own resolution; these are at ${size}x${size}, so"
        echo "compare how the error grows with the shrinking light, not the values). For the 10^4 light the"
        echo "reference holds only a few hundred camera rays that hit the light (of 268 million paths), so its"
        echo "variance, and the expectation drawn from it, is a low estimate."
        echo
        echo "| light area | expected relMSE at 64 spp | one 64-spp render (seed 5) | image mean of that render / reference |"
        echo "| --- | --- | --- | --- |"
        for size_label in 1e0 1e2 1e4; do
            local scene=scenes/stability/tiny_light_$size_label.json
            [ "$size_label" = 1e0 ] && scene=scenes/tncg15_room.json
            local ref="$refs/tiny_light_${size_label}_32.exr"
            "$hexray" render "$scene" --backend cpu --width $size --height $size --spp 64 --seed 5 \
                --variance --out "$out/tiny_64spp.exr" --quiet
            python3 - "$("$hexray" compare "$out/tiny_64spp.exr" "$ref" --json)" \
                "$(sed -n 's/.*spp=\([0-9]*\).*/\1/p' <(strings "$ref") | head -1)" "$size_label" <<'PY'
import json, sys
c, n_ref, label = json.loads(sys.argv[1]), float(sys.argv[2]), sys.argv[3]
expected = c["relmse_reference_noise"] * n_ref / 64
ratio = sum(c["ratio"]) / 3
print(f"| 1/{label} | {expected:.3g} | {c['relmse']:.3g} | {ratio:.3f} |")
PY
            rm -f "$out"/tiny_64spp*
        done
        echo
        echo "That the 10^4 light is still rendered without bias takes a render as long as the reference:"
        echo "\`cargo test --release --test tests stability_tiny_light:: -- --ignored\` (4.3 minutes on 2"
        echo "cores) gave, on 2026-11-23, image mean 0.69313 0.64466 0.59844 (s.e. 1.9e-2) against the"
        echo "reference's 0.68903 0.64481 0.59692 (s.e. 1.9e-2): z 0.15, −0.01, 0.06."
        echo
        echo "## What the tests measured"
        echo
        for module in stability_caustic stability_tiny_light stability_grazing stability_far_from_origin \
            stability_mirror_corridor stability_thin stability_mirror stability_shadow_colour; do
            echo "### \`tests/$module.rs\`"
            echo
            echo '```'
            awk -v m="$module" '
                /^test / { inmod = index($2, m "::") == 1; if (inmod) print; next }
                inmod && !/^(running|stack backtrace|note:|thread)/ && NF > 0 { print }' "$out/tests.log"
            echo '```'
            echo
        done
    } > docs/stability.md.tmp
    mv docs/stability.md.tmp docs/stability.md
    echo "wrote docs/stability.md"
}

case "${1:-}" in
    references) references ;;
    report) report ;;
    markdown) markdown ;;
    *) echo "usage: docs/stability.sh references|report|markdown" >&2; exit 2 ;;
esac
