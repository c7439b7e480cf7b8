#!/usr/bin/env bash
# docs/methods.md's charts of path tracing's relMSE against time (docs/figures/curves/), hexray's path tracer on both backends with
# Mitsuba 3's measured in the same run, just before and just after hexray's (these machines drift by tens
# of percent between hours, so an overlay read from a file of another day is not a measurement).
#
#   docs/figures/curves.sh [SCENE_NAME ...]        (default: cornell_box tncg15_room)
#
# Per scene: Mitsuba `path` (llvm_ad_rgb, all cores; benches/mitsuba_curve.py: doubling waves,
# then one sized to end just past the budget), then `hexray curve` on the CPU backend and, where
# an adapter exists, the GPU backend, then Mitsuba again. The table gives every series' relMSE at
# the budget (interpolated log-log between waves) and hexray's ratio to each Mitsuba curve: the
# ratio's range is the drift of the machine during the run. The chart shows the first Mitsuba
# curve (it exists when hexray's curve draws it); the table uses both.
#
# SECONDS_PER_CURVE (default 30) is the budget. References: cornell_box against Mitsuba's own
# 8192-spp render (tests/data/references/cornell_box_256.npy), tncg15_room against
# out/methods/refs/tncg15_room_256.exr (`docs/figures/methods.sh references`). Needs MITSUBA_PYTHON
# (default $HOME/mi/bin/python), a Python with the `mitsuba` package (Mitsuba 3). Output:
# docs/figures/curves/NAME/{curve.csv,mitsuba.csv,table.md,relmse_vs_*.{png,svg}}.
set -euo pipefail
cd "$(dirname "$0")/../.."
hexray=${HEXRAY:-target/release/hexray}
python=${MITSUBA_PYTHON:-$HOME/mi/bin/python}
seconds=${SECONDS_PER_CURVE:-30}
scenes=("$@")
[ ${#scenes[@]} -gt 0 ] || scenes=(cornell_box tncg15_room)

"$python" -c 'import mitsuba' 2> /dev/null ||
    { echo "no Mitsuba 3 at $python (MITSUBA_PYTHON): install Mitsuba 3 (pip install mitsuba) in a Python and point MITSUBA_PYTHON at it" >&2; exit 1; }
backends=cpu
"$hexray" info | grep '^\[' > /dev/null && backends=cpu,gpu

reference_of() {
    case $1 in
        cornell_box) echo tests/data/references/cornell_box_256.npy ;;
        *) echo "out/methods/refs/$1_256.exr" ;;
    esac
}

# Mitsuba's path-tracing curve with its variant column renamed to say when it ran.
mitsuba_curve() {
    local scene=$1 ref=$2 when=$3
    "$python" benches/mitsuba_curve.py "$scene" --ref "$ref" --seconds "$seconds" |
        awk -F, -v OFS=, -v when="$when" 'NR > 1 { $2 = "path (" when ")" } { print }'
}

for name in "${scenes[@]}"; do
    scene=scenes/$name.json ref=$(reference_of "$name") dir=docs/figures/curves/$name
    [ -f "$ref" ] || { echo "missing $ref: run docs/figures/methods.sh references" >&2; exit 1; }
    mkdir -p "$dir"
    echo "== $name: Mitsuba path, $seconds s (before)" >&2
    mitsuba_curve "$scene" "$ref" before > "$dir/mitsuba.csv"
    echo "== $name: hexray $backends path, $seconds s" >&2
    "$hexray" curve "$scene" --backend "$backends" --time "$seconds" --reference "$ref" \
        --overlay "$dir/mitsuba.csv" --out "$dir"
    echo "== $name: Mitsuba path, $seconds s (after)" >&2
    mitsuba_curve "$scene" "$ref" after | tail -n +2 >> "$dir/mitsuba.csv"
    python3 - "$dir" "$seconds" "$name" > "$dir/table.md" <<'PY'
import sys
sys.path.insert(0, "benches")
from curve_table import at, series
folder, budget, name = sys.argv[1], float(sys.argv[2]), sys.argv[3]
values = {k: at(v, budget) for k, v in series(folder).items()}
mitsuba = [v for k, v in values.items() if k.startswith("mitsuba") and v]
print(f"| {name}: series | relMSE at {budget:g} s | ratio to Mitsuba (before, after) |")
print("| --- | --- | --- |")
for k, v in values.items():
    if v is None:
        print(f"| {k} | ended before {budget:g} s | |")
        continue
    ratios = "" if k.startswith("mitsuba") else ", ".join(f"{v / m:.2f}" for m in mitsuba)
    print(f"| {k} | {v:.3e} | {ratios} |")
PY
    cat "$dir/table.md"
done
