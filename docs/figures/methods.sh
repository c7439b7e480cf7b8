#!/usr/bin/env bash
# Method against method: relMSE against render time for path tracing, light tracing, BDPT, SPPM and VCM on
# each backend, with Mitsuba 3's `path` and `ptracer` measured in the same run (scene by scene,
# Mitsuba's two curves right before hexray's), pictures at equal time, the cost of each method,
# and the generated part of docs/methods.md from all of it (between its "begin generated" and
# "end generated" lines; the text around them is written by hand).
#
#   docs/figures/methods.sh references   # deep 256x256 BDPT references of tncg15_room and glass_room
#                                        # (out/methods/refs, 25 min each on 2 cores; not committed);
#                                        # or copy the committed GPU path references there:
#                                        # cp tests/data/references/h100/*.exr out/methods/refs/
#                                        # (tests/data/references/README.md says what they are)
#   docs/figures/methods.sh run          # curves, Mitsuba, pictures, bench -> docs/figures/methods/
#                                        # (~55 min on 2 cores)
#   docs/figures/methods.sh readme       # only the README's picture (the default method against
#                                        # path 64 spp) -> docs/figures/tncg15_room.png
#   docs/figures/methods.sh markdown     # docs/methods.md's tables again from docs/figures/methods/
#   ONLY=caustic SECONDS_PER_CURVE=5 docs/figures/methods.sh run   # one scene, short curves (a trial)
#
# HEXRAY (default target/release/hexray) is the binary. Mitsuba is optional: with
# MITSUBA_PYTHON (default $HOME/mi/bin/python, a Python with the `mitsuba` package) missing, its
# curves are left out and the page says so. The GPU backend runs on whatever adapter wgpu finds
# (lavapipe here); without one, only the CPU's curves are drawn.
set -euo pipefail
cd "$(dirname "$0")/../.."
hexray=${HEXRAY:-target/release/hexray}
mitsuba_python=${MITSUBA_PYTHON:-$HOME/mi/bin/python}
mitsuba_curve_py=${MITSUBA_CURVE:-benches/mitsuba_curve.py}
out=docs/figures/methods
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

# Writes the commit (git describe --dirty) to FILE, described before the file is written:
# writing it first would mark the tree dirty.
stamp() {
    local commit
    commit=$(git describe --always --dirty 2> /dev/null || true)
    echo "$commit" > "$1"
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

# Whether FILE is the overlay CSV `hexray curve --overlay` reads: its header, then rows of six
# fields whose last four are numbers.
well_formed() {
    python3 - "$1" <<'PY'
import sys
lines = open(sys.argv[1]).read().splitlines()
def row_ok(row):
    fields = row.split(",")
    try:
        return len(fields) == 6 and all(float(x) == float(x) for x in fields[2:])
    except ValueError:
        return False
ok = lines[:1] == ["scene,variant,spp,seconds,rmse,relmse"] and all(row_ok(r) for r in lines[1:])
sys.exit(0 if ok else 1)
PY
}

run() {
    local backends=cpu
    have_gpu && backends=cpu,gpu
    mkdir -p "$out"
    stamp "$out/commit.txt"
    scene_list | while read -r name scene ref size; do
        [ -f "$ref" ] || { echo "missing $ref: run docs/figures/methods.sh references first" >&2; exit 1; }
        local dir=$out/$name
        mkdir -p "$dir"
        local overlay=()
        if have_mitsuba; then
            echo "== $name: Mitsuba path and ptracer, $seconds s each"
            # Measured again once if a row comes out malformed (seen once: a newline
            # replaced by another byte), rather than failing the run at `hexray curve`.
            for attempt in 1 2; do
                {
                    mitsuba_curve "$scene" "$ref" "$size" path
                    mitsuba_curve "$scene" "$ref" "$size" ptracer | tail -n +2
                } > "$dir/mitsuba.csv"
                well_formed "$dir/mitsuba.csv" && break
                echo "Mitsuba's curves of $name are malformed (attempt $attempt)" >&2
            done
            well_formed "$dir/mitsuba.csv" || exit 1
            overlay=(--overlay "$dir/mitsuba.csv")
        fi
        echo "== $name: hexray $backends, path, light, bdpt, $seconds s each"
        "$hexray" curve "$scene" --backend "$backends" --method path,light,bdpt,sppm,vcm,vcm-full,whitted \
            --time "$seconds" --reference "$ref" "${overlay[@]}" --out "$dir"
        "$hexray" compare "$ref" "$ref" --json > "$dir/reference.json"
        echo "== $name: pictures, 10 s each"
        for method in path light bdpt sppm vcm vcm-full whitted; do
            "$hexray" render "$scene" --backend cpu --method "$method" --time 10 \
                --width "$size" --height "$size" --seed 5 --out "out/methods/${name}_$method.exr" \
                --quiet
            cp "out/methods/${name}_$method.png" "$dir/$method.png"
        done
    done
    echo "== cost: hexray bench, 256x256, 32 samples or iterations"
    "$hexray" bench --backend "${backends}" --method path,light,bdpt,sppm,vcm,vcm-full,whitted --spp 32 \
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
    stamp "$out/readme_commit.txt"
    cp out/methods/readme_default.png docs/figures/tncg15_room.png
    cp out/methods/readme_path.png "$out/tncg15_room_512_path_64spp.png"
}

# The generated part of docs/methods.md (between its "begin generated" and "end generated"
# lines), from what `run` and `readme` left in docs/figures/methods/. The text around it is
# written by hand and kept as it is.
markdown() {
    python3 - "$out" "$seconds" <(scene_list) <<'PY' > "$out/generated.md.tmp"
import csv, json, math, os, sys
out, budget = sys.argv[1], float(sys.argv[2])
scenes = [l.split() for l in open(sys.argv[3]) if l.strip()]
rel = os.path.relpath(out, "docs")  # links are relative to docs/methods.md

sys.path.insert(0, "benches")
from curve_table import at, series as series_in

def fmt(x):
    return "–" if x is None else f"{x:.2e}"

def read(path):
    return open(path).read().strip() if os.path.exists(path) else None

methods = ["path", "light", "bdpt", "sppm", "vcm", "vcm-full", "whitted"]
refscenes = ("tncg15_room", "glass_room", "cornell_box")

# relMSE at the budget minus the reference's noise, per scene and series.
values, early, devices = {}, {}, {}
for name, scene, ref, size in scenes:
    s = series_in(f"{out}/{name}")
    if not s:
        continue
    noise = None
    if os.path.exists(f"{out}/{name}/reference.json"):
        noise = json.load(open(f"{out}/{name}/reference.json")).get("relmse_reference_noise")
    for b, pts in s.items():
        v = at(pts, budget)
        if v is None and pts and pts[-1][0] < budget:
            # The series' last wave ended before the budget (the next doubling would not have
            # fit): its value there, marked with its time, not an equal-time figure.
            v = pts[-1][1]
            early[(name, b)] = pts[-1][0]
        values[(name, b)] = None if v is None else v - (noise or 0.0)
    if os.path.exists(f"{out}/{name}/curve.csv"):
        for r in csv.DictReader(open(f"{out}/{name}/curve.csv")):
            devices[r["backend"].split()[1]] = r["device"].split(" (")[0]
names = [n for n, *_ in scenes if any(k[0] == n for k in values)]
series_names = []
for (n, b) in values:
    if b not in series_names:
        series_names.append(b)

def ratio(name, b):
    backend = b.split()[1]
    v, base = values.get((name, b)), values.get((name, f"hexray {backend} path"))
    return v / base if v is not None and base and base > 0 else None

machine = None
if os.path.exists(f"{out}/bench.json"):
    machine = json.load(open(f"{out}/bench.json")).get("machine")
commit = read(f"{out}/commit.txt")
gpu = devices.get("gpu")

print("<!-- begin generated by docs/figures/methods.sh markdown: edit the script, not this part -->\n")
print("## At equal time\n")
print(f"relMSE after {budget:.0f} s of rendering (after warm-up), minus the reference's own noise, as a")
print("ratio to the same backend's path tracer: below 1 is better than path tracing. The geometric")
print("mean is over the three reference scenes.\n")
cols = [n for n in names]
print("| backend | method | " + " | ".join(cols) + " | geometric mean |")
print("| --- | --- | " + " | ".join("---" for _ in cols) + " | --- |")
for be in ("cpu", "gpu"):
    for m in methods:
        b = f"hexray {be} {m}"
        if b not in series_names:
            continue
        rs = {n: ratio(n, b) for n in cols}
        g3 = [rs[n] for n in refscenes if n in rs]
        g = math.exp(sum(math.log(r) for r in g3) / len(g3)) if g3 and all(g3) else None
        best = lambda n: all(rs[n] is not None and (ratio(n, f"hexray {be} {o}") is None or rs[n] <= ratio(n, f"hexray {be} {o}")) for o in methods)
        cells = ["–" if rs[n] is None else (f"**{rs[n]:.2f}**" if best(n) else f"{rs[n]:.2f}") for n in cols]
        print(f"| {be} | {m} | " + " | ".join(cells) + f" | {'–' if g is None else f'{g:.2f}'} |")
print()
how = f"`docs/figures/methods.sh run`, {budget:.0f} s a curve"
if machine:
    how += f", on {machine}"
if gpu:
    how += f"; the GPU backend on lavapipe (`{gpu}`)" if "llvmpipe" in gpu else f"; the GPU backend on `{gpu}`"
if commit:
    how += f"; commit {commit}"
print(f"How this was measured: {how}. The curves, pictures and bench rows are in")
print(f"[{rel}/]({rel}/).\n")
print(f"The same relMSE values, with Mitsuba 3's `path` and `ptracer` (`llvm_ad_rgb`, all cores)")
print("measured in the same run, scene by scene, just before hexray's curves (not alternated, so")
print("read them as a guide, not as a ratio):\n")
print("| series | " + " | ".join(cols) + " |")
print("| --- | " + " | ".join("---" for _ in cols) + " |")
for b in series_names:
    cells = []
    for n in cols:
        v = values.get((n, b))
        cells.append(fmt(v) + (f" (at {early[(n, b)]:.1f} s)" if (n, b) in early else ""))
    print(f"| {b} | " + " | ".join(cells) + " |")
print()
print("## Charts and pictures\n")
for name, scene, ref, size in scenes:
    if name not in names:
        continue
    print(f"### {name}\n")
    print(f"`{scene}`, {size}x{size}, against `{ref}`.\n")
    print(f"![{name}: relMSE against time]({rel}/{name}/relmse_vs_seconds.png)\n")
    pics = [m for m in methods if os.path.exists(f"{out}/{name}/{m}.png")]
    if pics:
        print("Pictures, 10 s each on the CPU backend:\n")
        print("| " + " | ".join(pics) + " |")
        print("| " + " | ".join("---" for _ in pics) + " |")
        print("| " + " | ".join(f"![{m}]({rel}/{name}/{m}.png)" for m in pics) + " |\n")
if os.path.exists(f"{out}/readme_default.json"):
    print("## The default against path tracing\n")
    print("The README's picture: `hexray render` with its defaults (tncg15_room, 512x512, vcm, CPU) for")
    print("as long as path tracing takes for 64 samples per pixel, both compared with the 256x256")
    print("reference `out/methods/refs/tncg15_room_256.exr` as 2x2 block means.\n")
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
    r = vals["default"] / vals["path"]
    print(f"\nvcm's relMSE is {r:.3f} of path tracing's; at equal time (relMSE x seconds, since a")
    print(f"method's variance falls as 1/time) {r * secs['default'] / secs['path']:.3f}.")
    rc = read(f"{out}/readme_commit.txt")
    print(f"How this was measured: `docs/figures/methods.sh readme`{f'; commit {rc}' if rc else ''}.\n")
    print(f"| path, 64 spp | vcm, as long |")
    print("| --- | --- |")
    print(f"| ![path, 64 spp]({rel}/tncg15_room_512_path_64spp.png) | ![vcm]({os.path.relpath('docs/figures', 'docs')}/tncg15_room.png) |\n")
if os.path.exists(f"{out}/bench.json"):
    rows = json.load(open(f"{out}/bench.json"))["rows"]
    spp = rows[0]["spp"] if rows else 0
    print("## Cost\n")
    print(f"M camera paths per second, 256x256, {spp} samples (`hexray bench --method")
    print(f"path,light,bdpt,sppm,vcm,vcm-full,whitted --spp {spp}`; for every method but path and whitted a camera path")
    print("is one pixel's iteration, its light subpath included):\n")
    keys = []
    for r in rows:
        k = (r["scene"], r["backend"])
        if k not in keys:
            keys.append(k)
    print("| method | " + " | ".join(f"{s} {b}" for s, b in keys) + " |")
    print("| --- | " + " | ".join("---" for _ in keys) + " |")
    for m in methods:
        cells = []
        for s, b in keys:
            r = next((r for r in rows if r["scene"] == s and r["backend"] == b and r["method"] == m), None)
            cells.append("–" if r is None else f"{r['camera_paths_per_second'] / 1e6:.3f}")
        if any(c != "–" for c in cells):
            print(f"| {m} | " + " | ".join(cells) + " |")
    print(f"\nThe rows with rays per path and device: [{rel}/bench.txt]({rel}/bench.txt).\n")
print("<!-- end generated -->")
PY
    python3 - "$out/generated.md.tmp" docs/methods.md <<'PY'
import sys
block, page = open(sys.argv[1]).read(), sys.argv[2]
text = open(page).read()
begin, end = "<!-- begin generated", "<!-- end generated -->"
i, j = text.index(begin), text.index(end) + len(end)
open(page + ".tmp", "w").write(text[:i] + block.rstrip("\n") + text[j:])
PY
    mv docs/methods.md.tmp docs/methods.md
    rm -f "$out/generated.md.tmp"
    echo "wrote docs/methods.md"
}

case "${1:-}" in
    references) references ;;
    run) run ;;
    readme) readme; markdown ;;
    markdown) markdown ;;
    *) sed -n '2,22p' "$0"; exit 2 ;;
esac
