#!/usr/bin/env bash
# The generated part of docs/stability.md: for each stability scene (scenes/stability/), a CPU and
# a GPU picture side by side and the relMSE-against-time curve of both backends, all of the path
# tracer (--method path), and the tiny lights' expected error. The tests' own output goes to
# docs/figures/stability/tests.log.
#
#   docs/figures/stability.sh references   # the long CPU references (tests/data/references/stability/;
#                                          # about 80 min on 2 cores: the 10^4 tiny light dominates)
#   ONLY=door_ajar\|enclosed_light docs/figures/stability.sh references   # only those
#   docs/figures/stability.sh report       # pictures, curves, test values -> docs/figures/stability/,
#                                          # then docs/stability.md (~25 min)
#   docs/figures/stability.sh markdown     # docs/stability.md again from docs/figures/stability/
#
# HEXRAY (default target/release/hexray) is the binary; build it first with
# `cargo build --release`. The GPU backend runs on whatever adapter wgpu finds (lavapipe here).
set -euo pipefail
cd "$(dirname "$0")/../.."
hexray=${HEXRAY:-target/release/hexray}
refs=tests/data/references/stability
out=docs/figures/stability
# Every curve and reference is 32x32 pixels (the tests' size); pictures are 128x128.
size=32
# Seeds: references 1000000 (apart from every test's and picture's seed).
ref_seed=1000000

# name, scene file, reference spp, method (unbiased on that scene: path, or bdpt where path
# tracing's error falls too slowly). ONLY=name1\|name2 keeps those references (the others are
# left as they are).
reference_list() {
    cat <<'EOF'
caustic scenes/stability/caustic.json 65536 path
tiny_light_1e2 scenes/stability/tiny_light_1e2.json 65536 path
tiny_light_1e0 scenes/tncg15_room.json 65536 path
glass_room scenes/glass_room.json 65536 path
tiny_light_1e4 scenes/stability/tiny_light_1e4.json 262144 path
grazing scenes/stability/grazing.json 16384 path
mirror_corridor scenes/stability/mirror_corridor.json 16384 path
thin_slab scenes/stability/thin_slab.json 16384 path
cornell_box scenes/cornell_box.json 262144 path
door_ajar scenes/stability/door_ajar.json 524288 path
mirror_caustic scenes/stability/mirror_caustic.json 131072 bdpt
enclosed_light scenes/stability/enclosed_light.json 65536 bdpt
tiny_light_1e2_bdpt scenes/stability/tiny_light_1e2.json 32768 bdpt
EOF
}

references() {
    mkdir -p "$refs"
    reference_list | grep -e "^\(${ONLY:-.*}\) " | while read -r name scene spp method; do
        echo "== $name: $spp spp of $method"
        "$hexray" reference "$scene" --backend cpu --method "$method" --width $size --height $size \
            --spp "$spp" --seed $ref_seed --out "$refs/${name}_32.exr" --quiet
        rm -f "$refs/${name}_32.film"
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

# name, scene, reference (for the curve; "-" for none), what the picture shows. The robustness
# scenes only: the scenes where methods differ (the caustic, the tiny lights 1e0 and 1e2,
# grazing, the mirror corridor, the thin slab) are the atlas's, every method on both backends
# (docs/atlas.sh).
report_list() {
    cat <<'EOF'
tiny_light_1e4 scenes/stability/tiny_light_1e4.json tiny_light_1e4_32.exr
far_from_origin_1e3 scenes/stability/tncg15_translated_1e3.json tiny_light_1e0_32.exr
far_from_origin_1e4 scenes/stability/tncg15_translated_1e4.json tiny_light_1e0_32.exr
far_from_origin_1e5 scenes/stability/tncg15_translated_1e5.json tiny_light_1e0_32.exr
far_from_origin_1e6 scenes/stability/tncg15_translated_1e6.json tiny_light_1e0_32.exr
thin_box scenes/stability/thin_box.json -
mirror_doubled scenes/stability/tncg15_mirror_doubled.json -
shadow_colour scenes/stability/tncg15_umbra_view.json -
EOF
}

report() {
    mkdir -p "$out"
    # Described before the file is written: writing it first would mark the tree dirty.
    local commit
    commit=$(git describe --always --dirty 2> /dev/null || true)
    echo "$commit" > "$out/commit.txt"
    local adapter
    adapter=$("$hexray" info 2>/dev/null | sed -n 's/^\[0\] //p' | head -1)
    echo "$(nproc) cores ($(sed -n 's/^model name\s*: //p' /proc/cpuinfo | head -1)); GPU backend on ${adapter:-no adapter}" \
        > "$out/machine.txt"
    # The tests' measured values, one module at a time, in test order.
    cargo test --release --test tests stability_ -- --nocapture --test-threads 1 \
        > "$out/tests.log" 2>&1 || true
    report_list | while read -r name scene ref; do
        echo "== $name"
        mkdir -p "$out/$name"
        for b in cpu gpu; do
            "$hexray" render "$scene" --backend $b --method path --width 128 --height 128 --spp 64 --seed 3 \
                --out "$out/$name/$b.exr" --quiet
            rm -f "$out/$name/$b.exr"
        done
        if [ "$ref" != "-" ]; then
            "$hexray" curve "$scene" --backend cpu,gpu --method path --reference "$refs/$ref" --time 10 \
                --out "$out/$name" >/dev/null
            rm -f "$out/$name"/*.svg
        fi
    done
    markdown
}

# The generated part of docs/stability.md (between its "begin generated" and "end generated"
# lines) from what `report` left in docs/figures/stability/; the text around it is written by
# hand and kept as it is. Renders the tiny lights' 64-spp table (seconds on the CPU).
markdown() {
    local block=$out/generated.md.tmp
    {
        echo "<!-- begin generated by docs/figures/stability.sh markdown: edit the script, not this part -->"
        echo
        echo "| light area | expected relMSE at 64 spp | one 64-spp render (seed 5) | image mean of that render / reference |"
        echo "| --- | --- | --- | --- |"
        for size_label in 1e0 1e2 1e4; do
            local scene=scenes/stability/tiny_light_$size_label.json
            [ "$size_label" = 1e0 ] && scene=scenes/tncg15_room.json
            local ref="$refs/tiny_light_${size_label}_32.exr"
            "$hexray" render "$scene" --backend cpu --method path --width $size --height $size \
                --spp 64 --seed 5 --variance --out "$out/tiny_64spp.exr" --quiet
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
        echo "How this was measured: \`docs/figures/stability.sh markdown\` (path tracing, CPU, ${size}x${size},"
        echo "against \`$refs/\`)."
        echo
        echo "## Pictures and curves of the robustness scenes (path tracing)"
        echo
        echo "The scenes where methods differ (the caustic, the tiny lights 1e0 and 1e2, grazing, the mirror"
        echo "corridor, the thin slab) are in the [atlas](atlas.md), every method on both backends."
        echo
        echo "Pictures: 128x128, 64 spp per backend (seed 3). Curves: ${size}x${size} against the long CPU"
        echo "references, 10 s per backend; \"relMSE at 10 s\" is the last doubling wave finished within 10 s."
        echo "How this was measured: \`docs/figures/stability.sh report\`$( [ -f "$out/machine.txt" ] && echo ", on $(cat "$out/machine.txt")")$( [ -f "$out/commit.txt" ] && echo "; commit $(cat "$out/commit.txt")")."
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
            echo "### $name"
            echo
            echo "\`$scene\`"
            echo
            echo "| CPU | GPU |"
            echo "| --- | --- |"
            echo "| ![cpu](figures/stability/$name/cpu.png) | ![gpu](figures/stability/$name/gpu.png) |"
            echo
            if [ "$ref" != "-" ]; then
                echo "![relMSE against time](figures/stability/$name/relmse_vs_seconds.png)"
                echo
            fi
        done
        echo "<!-- end generated -->"
    } > "$block"
    python3 - "$block" docs/stability.md <<'PY'
import sys
block, page = open(sys.argv[1]).read(), sys.argv[2]
text = open(page).read()
begin, end = "<!-- begin generated", "<!-- end generated -->"
i, j = text.index(begin), text.index(end) + len(end)
open(page + ".tmp", "w").write(text[:i] + block.rstrip("\n") + text[j:])
PY
    mv docs/stability.md.tmp docs/stability.md
    rm -f "$block"
    echo "wrote docs/stability.md"
}

case "${1:-}" in
    references) references ;;
    report) report ;;
    markdown) markdown ;;
    *) echo "usage: docs/figures/stability.sh references|report|markdown" >&2; exit 2 ;;
esac
