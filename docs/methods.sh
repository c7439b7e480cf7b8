#!/usr/bin/env bash
# Method against method: relMSE against render time for path tracing, light tracing, BDPT, SPPM and VCM on
# each backend, with Mitsuba 3's `path` and `ptracer` measured in the same run (scene by scene,
# Mitsuba's two curves right before hexray's), pictures at equal time, the cost of each method,
# and docs/methods.md from all of it.
#
#   docs/methods.sh references   # deep 256x256 BDPT references of tncg15_room and glass_room
#                                # (out/methods/refs, 25 min each on 2 cores; not committed);
#                                # or copy the committed GPU path references there:
#                                # cp tests/data/references/h100/*.exr out/methods/refs/
#                                # (tests/data/references/README.md says what they are)
#   docs/methods.sh run          # curves, Mitsuba, pictures, bench -> docs/methods/
#                                # (~55 min)
#   docs/methods.sh readme       # only the README's picture (the default method against path 64 spp)
#   docs/methods.sh markdown     # docs/methods.md again from what `run` left in docs/methods/
#   ONLY=caustic SECONDS_PER_CURVE=5 docs/methods.sh run   # one scene, short curves (a trial)
#
# HEXRAY (default target/release/hexray) is the binary. Mitsuba is optional: with
# MITSUBA_PYTHON (default $HOME/mi/bin/python, see ../shared/mitsuba/README.md) missing, its
# curves are left out and the page says so. The GPU backend runs on whatever adapter wgpu finds
# (lavapipe here); without one, only the CPU's curves are drawn.
set -euo pipefail
cd "$(dirname "$0")/.."
hexray=${HEXRAY:-target/release/hexray}
mitsuba_python=${MITSUBA_PYTHON:-$HOME/mi/bin/python}
mitsuba_curve_py=${MITSUBA_CURVE:-benches/mitsuba_curve.py}
out=docs/methods
refs=out/methods/refs
seconds=${SECONDS_PER_CURVE:-30}

# name, scene file, reference (a render with NAME_var beside it), size; ONLY=name1\|name2
# keeps those scenes.
scene_list() {
    all_scenes | grep -e "^\(${ONLY:-.*}\) "
}

all_scenes() {
    cat <<EOF
tncg15_room scenes/tncg15_room.json $refs/tncg15_room_256.exr 256
glass_room scenes/glass_room.json $refs/glass_room_256.exr 256
cornell_box scenes/cornell_box.json tests/data/references/cornell_box_256.npy 256
caustic scenes/stability/caustic.json tests/data/references/stability/caustic_32.exr 32
tiny_light_1e2 scenes/stability/tiny_light_1e2.json tests/data/references/stability/tiny_light_1e2_32.exr 32
EOF
}

references() {
    mkdir -p "$refs"
    local seed=777
    for name in tncg15_room glass_room; do
        echo "== $name: BDPT for 1500 s"
        "$hexray" reference "scenes/$name.json" --backend cpu --method bdpt --time 1500 \
            --width 256 --height 256 --seed $seed --out "$refs/${name}_256.exr" --quiet
        seed=$((seed + 1))
    done
}

have_mitsuba() {
    [ -x "$mitsuba_python" ] && "$mitsuba_python" -c 'import mitsuba' 2> /dev/null
}

have_gpu() {
    "$hexray" info | grep '^\[' > /dev/null
}

# Mitsuba's curve of one integrator (benches/mitsuba_curve.py: doubling waves, then one that
# ends just past the budget).
mitsuba_curve() {
    local scene=$1 ref=$2 size=$3 integrator=$4
    "$mitsuba_python" "$mitsuba_curve_py" "$scene" --ref "$ref" --res "$size" \
        --seconds "$seconds" --integrator "$integrator"
}

run() {
    local backends=cpu
    have_gpu && backends=cpu,gpu
    mkdir -p "$out"
    scene_list | while read -r name scene ref size; do
        [ -f "$ref" ] || { echo "missing $ref: run docs/methods.sh references first" >&2; exit 1; }
        local dir=$out/$name
        mkdir -p "$dir"
        local overlay=()
        if have_mitsuba; then
            echo "== $name: Mitsuba path and ptracer, $seconds s each"
            {
                mitsuba_curve "$scene" "$ref" "$size" path
                mitsuba_curve "$scene" "$ref" "$size" ptracer | tail -n +2
            } > "$dir/mitsuba.csv"
            overlay=(--overlay "$dir/mitsuba.csv")
        fi
        echo "== $name: hexray $backends, path, light, bdpt, $seconds s each"
        "$hexray" curve "$scene" --backend "$backends" --method path,light,bdpt,sppm,vcm,vcm-full \
            --time "$seconds" --reference "$ref" "${overlay[@]}" --out "$dir"
        "$hexray" compare "$ref" "$ref" --json > "$dir/reference.json"
        echo "== $name: pictures, 10 s each"
        for method in path light bdpt sppm vcm vcm-full; do
            "$hexray" render "$scene" --backend cpu --method "$method" --time 10 \
                --width "$size" --height "$size" --seed 5 --out "out/methods/${name}_$method.exr" \
                --quiet
            cp "out/methods/${name}_$method.png" "$dir/$method.png"
        done
    done
    echo "== cost: hexray bench, 256x256, 32 samples or iterations"
    "$hexray" bench --backend "${backends}" --method path,light,bdpt,sppm,vcm,vcm-full --spp 32 \
        --out "$out/bench.json" > "$out/bench.txt"
    markdown
}

# The README's picture: `hexray render`'s default scene and size (tncg15_room, 512x512) with
# the default method, for as long as the old default (path, 64 spp) takes, both on the CPU
# and compared with the 256x256 reference as 2x2 block means.
readme() {
    local log=out/methods/readme_path.log
    mkdir -p out/methods
    echo "== the README's picture: path 64 spp, then the default method for as long"
    "$hexray" render scenes/tncg15_room.json --backend cpu --method path --spp 64 --seed 5 --variance \
        --out out/methods/readme_path.exr 2> "$log"
    local t
    t=$(sed -n 's/^rendered 64 spp with path in \([0-9.]*\) s.*/\1/p' "$log")
    [ -n "$t" ] || { cat "$log" >&2; exit 1; }
    "$hexray" render scenes/tncg15_room.json --backend cpu --time "$t" --seed 5 --variance \
        --out out/methods/readme_default.exr 2> out/methods/readme_default.log
    for which in path default; do
        "$hexray" compare "out/methods/readme_$which.exr" "$refs/tncg15_room_256.exr" --json \
            > "$out/readme_$which.json"
        grep '^rendered' "out/methods/readme_$which.log" > "$out/readme_$which.txt"
    done
    cp out/methods/readme_default.png docs/tncg15_room.png
    cp out/methods/readme_path.png "$out/tncg15_room_512_path_64spp.png"
}

markdown() {
    python3 - "$out" "$seconds" <(scene_list) <<'PY' > docs/methods.md.tmp
import csv, json, math, os, sys
out, budget = sys.argv[1], float(sys.argv[2])
scenes = [l.split() for l in open(sys.argv[3]) if l.strip()]

sys.path.insert(0, "benches")
from curve_table import at, series as series_in

def series(name):
    return series_in(f"{out}/{name}")

def fmt(x):
    return "–" if x is None else f"{x:.2e}"

print("# Method against method\n")
print("Generated by `docs/methods.sh run` (this page alone: `docs/methods.sh markdown`). relMSE = mean")
print("(x − r)²/(r² + 0.01) over pixel-channels, against the reference named per scene, at equal render")
print(f"time after warm-up ({budget:.0f} s per curve), on the machine in each chart's caption. The")
print("reference's own noise (mean var_r/(r² + 0.01), from its variance file) is subtracted in the")
print("tables (E (x − r)² = var_x + var_r) and given with them. Mitsuba 3's `path` and `ptracer`")
print("(`llvm_ad_rgb`, all cores) were measured in the same run, scene by scene, just before hexray's")
print("curves, with `benches/mitsuba_curve.py` (doubling waves, then one sized to end just past the")
print("budget, so its row is interpolated at the budget like hexray's). Measured in the same run but")
print("not alternated: no ratio to Mitsuba is drawn here; the closing notes of the issues give")
print("alternated ones. A row marked with a time is the value of a curve that ended before the budget.\n")
print("Light tracing (`light`) sees nothing through a mirror or glass, so its error has a floor")
print("wherever the camera sees one; BDPT (`bdpt`) is unbiased everywhere; SPPM (`sppm`) and VCM (`vcm`, at each")
print("camera subpath's first diffuse vertex, and `vcm-full`, as published) merge photons and are consistent, not")
print("unbiased (their error includes the merging bias). The methods themselves:")
print("`src/cpu/path.rs`, `src/cpu/light_path.rs`, `src/cpu/bdpt.rs` and `src/subpath.rs`.\n")
summary = []
for name, scene, ref, size in scenes:
    s = series(name)
    if not s:
        continue
    noise = None
    if os.path.exists(f"{out}/{name}/reference.json"):
        noise = json.load(open(f"{out}/{name}/reference.json")).get("relmse_reference_noise")
    print(f"## {name}\n")
    print(f"`{scene}`, {size}x{size}, reference `{ref}` (its own relMSE noise {fmt(noise)}).\n")
    print(f"![{name}: relMSE against time]({os.path.basename(out)}/{name}/relmse_vs_seconds.png)\n")
    print(f"| series | relMSE at {budget:.0f} s | minus the reference's noise | ratio to hexray path (same backend) |")
    print("| --- | --- | --- | --- |")
    vals, early = {}, {}
    for b, pts in s.items():
        v = at(pts, budget)
        if v is None and pts and pts[-1][0] < budget:
            # The series' last wave ended before the budget (the next doubling would not have
            # fit): its value there, marked with its time, not an equal-time figure.
            v = pts[-1][1]
            early[b] = pts[-1][0]
        vals[b] = v
    for b, v in vals.items():
        c = None if v is None else v - (noise or 0.0)
        backend = b.split()[1] if b.startswith("hexray") else None
        base = vals.get(f"hexray {backend} path") if backend else None
        ratio = None
        if c is not None and base is not None:
            cb = base - (noise or 0.0)
            ratio = c / cb if cb > 0 else None
        when = f" (at {early[b]:.1f} s)" if b in early else ""
        print(f"| {b}{when} | {fmt(v)} | {fmt(c)} | {'–' if ratio is None else f'{ratio:.2f}'} |")
        summary.append((name, b, c, ratio))
    print()
    pics = [m for m in ("path", "light", "bdpt", "sppm", "vcm", "vcm-full") if os.path.exists(f"{out}/{name}/{m}.png")]
    if pics:
        print("Pictures, 10 s each on the CPU backend: " + ", ".join(pics) + ".\n")
        print("| " + " | ".join(pics) + " |")
        print("| " + " | ".join("---" for _ in pics) + " |")
        print("| " + " | ".join(f"![{m}]({os.path.basename(out)}/{name}/{m}.png)" for m in pics) + " |\n")
# The default method: per backend, the method with the lowest relMSE at the budget on the three
# reference scenes (the geometric mean of its ratios to path breaks a split decision).
refscenes = ("tncg15_room", "glass_room", "cornell_box")
rows = [(n, b, c, r) for n, b, c, r in summary if n in refscenes and b.startswith("hexray")]
if rows:
    print("## The default method\n")
    print("`hexray render`'s default is the method with the lowest error at equal time on the three")
    print(f"reference scenes on each backend (relMSE at {budget:.0f} s minus the reference's noise, as")
    print("above; ratio to the backend's path tracer, and its geometric mean over the scenes):\n")
    backends = sorted({b.split()[1] for _, b, _, _ in rows})
    methods = ["path", "light", "bdpt", "sppm", "vcm", "vcm-full"]
    print("| backend | method | " + " | ".join(refscenes) + " | geometric mean |")
    print("| --- | --- | " + " | ".join("---" for _ in refscenes) + " | --- |")
    for be in backends:
        for m in methods:
            rs = [next((r for n, b, c, r in rows if n == sc and b == f"hexray {be} {m}"), None) for sc in refscenes]
            if all(r is None for r in rs):
                continue
            g = math.exp(sum(math.log(r) for r in rs) / len(rs)) if all(r for r in rs) else None
            cells = ["–" if r is None else f"{r:.2f}" for r in rs]
            print(f"| {be} | {m} | " + " | ".join(cells) + f" | {'–' if g is None else f'{g:.2f}'} |")
    print()
    # Measured on lent GPUs (docs/bench/2026-11-26_h100, 2026-11-27_h200), not by this script.
    print("On hardware GPUs the margins differ. On an NVIDIA H100 (2026-11-26, 6 s curves, the GPU's own")
    print("path-traced references) path tracing led at 256x256 by the geometric mean: vcm 1.06, 0.79 and")
    print("5.88 of path, geometric mean 1.70 (1.14 without subtracting the references' noise). At")
    print("512x512 (4 s, one render each) vcm was 0.47 and 0.34 of path on tncg15_room and glass_room; since")
    print("the grid's parallel prefix sum, sppm leads there (0.29 and 0.25, vcm 0.44 and 0.30).")
    print("Its bidirectional kernels were 29 – 41x slower than its path tracer per camera path at 256x256,")
    print("against 3.6 – 4.8x on the CPU ([docs/gpu.md](gpu.md#on-a-hardware-gpu-nvidia-h100)). On an")
    print("NVIDIA H200 (2026-11-27, build f875e5f, with vcm's two camera subpaths behind mirrors and glass),")
    print("vcm leads at 256x256 by a small margin: 0.53, 0.43 and 3.89 of path, geometric mean 0.96; at")
    print("512x512 it is 0.24 and 0.19 of path on tncg15_room and glass_room, sppm 0.24 and 0.22")
    print("([docs/gpu.md](gpu.md#on-a-hardware-gpu-nvidia-h200)). This page")
    print("is generated by `docs/methods.sh`, and this paragraph is kept in its generator. Those GPU")
    print("figures are from before 2026-11-27 11:30 UTC, when the merge radius's default went from 0.003")
    print("to 0.01 of the scene radius (src/merging.rs, `DEFAULT_RADIUS_FACTOR`); on the H200 that radius")
    print("had 0.80, 1.00 and 1.12 of vcm's relMSE at 256x256 and 1.20 – 2.82 at 512x512. At 0.01, in")
    print("the same call (docs/bench/2026-11-27_h200/radius_equal_time.txt), vcm was 0.45, 0.43 and 4.6 of")
    print("path at 256x256 (geometric mean 0.96) and sppm 0.78, 0.82 and 27 (2.6): on a hardware GPU vcm")
    print("leads (on lavapipe sppm did then, before vcm merged within the clearance). The GPU backend is meant for hardware GPUs, and its")
    print("default follows them: vcm on both backends.\n")
    print("Runs of this page before 2026-11-27 14:00 UTC (build cdd2a5f) measured VCM as published")
    print("under the name `vcm`: that method is now `vcm-full`, and `vcm` ends each camera subpath at its")
    print("first diffuse vertex ([docs/performance.md](performance.md#vcm-at-the-first-diffuse-vertex-kept-2026-11-27)).")
    print("Since 2026-11-27 18:00 UTC (build c328219) vcm also merges within each camera vertex's")
    print("clearance, the distance to the nearest surface off its plane, with a default radius of 0.03")
    print("of the scene radius (sppm and vcm-full keep 0.01; [docs/performance.md](performance.md#merging-within-the-clearance-kept-2026-11-27-evening)):")
    print("the curves above are of that vcm. Against Mitsuba's `path`, alternated in one run of")
    print("`benches/methods_vs_mitsuba.sh` on 2026-11-27, 17:51 – 18:07 UTC (not this script; 256x256,")
    print("30 s, 2 cores), vcm had 0.021 and 0.030 of its relMSE on tncg15_room and glass_room, bdpt")
    print("0.123 and 0.086, sppm 0.085 and 0.064")
    print("([docs/bench](bench/methods_vs_mitsuba_2026-11-27_clearance.md)): a record of that run, not a")
    print("measurement of this page's machine; rerun that script for today's ratios. The hardware GPUs' figures")
    print("above are from before it.")
    print("So vcm is the default on both backends.\n")
if os.path.exists(f"{out}/readme_default.json"):
    print("## The README's picture\n")
    print("`hexray render` with its defaults (tncg15_room, 512x512, CPU), the old default (path, 64 spp)")
    print("against the default method for as long, both compared with the 256x256 reference")
    print("out/methods/refs/tncg15_room_256.exr as 2x2 block means (`docs/methods.sh readme`; on")
    print("2026-11-27, on an Intel Xeon VM, against the GPU path reference of")
    print("`tests/data/references/h100/` copied there, not the CPU BDPT reference of the curves above):\n")
    print("| render | relMSE | minus the reference's noise |")
    print("| --- | --- | --- |")
    vals, secs = {}, {}
    for which in ("path", "default"):
        c = json.load(open(f"{out}/readme_{which}.json"))
        line = open(f"{out}/readme_{which}.txt").read().strip()
        n = c.get("relmse_reference_noise") or 0.0
        vals[which] = c["relmse"] - n
        secs[which] = float(line.split(" in ")[1].split(" s")[0])
        print(f"| {line} | {c['relmse']:.2e} | {c['relmse'] - n:.2e} |")
    ratio = vals['default'] / vals['path']
    longer = "longer" if secs['default'] > secs['path'] else "shorter"
    print(f"\nRatio default / old default: {ratio:.3f}. A time budget ends after the iteration that")
    print(f"crosses it, so the default ran {longer} ({secs['default']:.2f} s against {secs['path']:.2f} s); at equal time")
    print("(relMSE x seconds, the inverse of the efficiency, since a method's variance falls as")
    print(f"1/time): {ratio * secs['default'] / secs['path']:.3f}.\n")
    print(f"![the default render]({'tncg15_room.png'}) ![path, 64 spp]({os.path.basename(out)}/tncg15_room_512_path_64spp.png)\n")
if os.path.exists(f"{out}/bench.txt"):
    print("## Cost\n")
    print("`hexray bench --method path,light,bdpt,sppm,vcm --spp 32` (256x256; for every method but")
    print("path a \"camera path\" is one pixel's iteration, its light subpath included; rays per path are")
    print("counted on the CPU):\n")
    print("```")
    print(open(f"{out}/bench.txt").read().rstrip())
    print("```\n")
PY
    mv docs/methods.md.tmp docs/methods.md
    echo "wrote docs/methods.md"
}

case "${1:-}" in
    references) references ;;
    run) run ;;
    readme) readme; markdown ;;
    markdown) markdown ;;
    *) sed -n '2,16p' "$0"; exit 2 ;;
esac
