#!/usr/bin/env bash
# The failure atlas: where each light-transport method fails. Every scene below that has a 32x32
# reference, every method of METHODS that the binary knows, on both backends, rendered for the
# same time and compared with the reference; then docs/atlas.md (its generated part) from that.
#
#   docs/atlas.sh run        # renders -> docs/figures/atlas/ (results.csv, best.csv,
#                            # montage_{cpu,gpu}.png, commit.txt, date.txt, machine.txt, runtime.txt),
#                            # then docs/atlas.md
#   docs/atlas.sh markdown   # docs/atlas.md (and best.csv) again from docs/figures/atlas/results.csv
#
# Run time: one render of ATLAS_SECONDS (default 4) per scene, method and backend, plus the
# start-up and comparison around it, measured on 2 cores (AMD EPYC, lavapipe) at 0.5 s per CPU
# render and 1.0 s per GPU render (its 1-spp warm-up included: lavapipe compiles a scene's
# kernels once, then reads them from its disk cache; on a cold cache a warm-up takes up to
# about 13 s, outside the timed render). So 11 scenes x 9 methods x (4.5 s CPU + 5 s GPU) = 16 min.
# Measured: the whole run from a clean clone, 900 s (15 min 1 s wall clock, 2026-11-29).
#
# Knobs (environment): HEXRAY (default target/release/hexray); ATLAS_SECONDS (the time per
# render); ATLAS_BACKENDS (default "cpu gpu"; gpu is left out when wgpu finds no adapter);
# ONLY=name1\|name2 (scenes); METHODS (default the list below); ATLAS_KEEP=1 keeps the rows of
# the methods not in METHODS in results.csv (to render one method again). A method the binary does not list
# in `hexray render --help` is skipped with a note in results.csv; a render that fails (say, a
# method without a GPU kernel) is recorded as failed with its first error line.
# The references are tests/data/references/stability/NAME_32.exr, made by
# `docs/figures/stability.sh references` (its reference_list says each one's method and spp).
set -euo pipefail
cd "$(dirname "$0")/.."
hexray=${HEXRAY:-target/release/hexray}
all_methods="path light bdpt sppm vcm vcm-full whitted photon-map radiosity"
methods=${METHODS:-$all_methods}
backends=${ATLAS_BACKENDS:-cpu gpu}
seconds=${ATLAS_SECONDS:-4}
refs=tests/data/references/stability
out=docs/figures/atlas
work=out/atlas
size=32
seed=11
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-/tmp}

# name, scene file, reference (in $refs), family (the key of the "why it fails" lines below)
all_scenes() {
    cat <<'EOF'
cornell_box scenes/cornell_box.json cornell_box_32.exr diffuse_room
tncg15_room scenes/tncg15_room.json tiny_light_1e0_32.exr specular_room
glass_room scenes/glass_room.json glass_room_32.exr specular_room
caustic scenes/stability/caustic.json caustic_32.exr caustic
mirror_caustic scenes/stability/mirror_caustic.json mirror_caustic_32.exr mirror_caustic
enclosed_light scenes/stability/enclosed_light.json enclosed_light_32.exr enclosed_light
tiny_light_1e2 scenes/stability/tiny_light_1e2.json tiny_light_1e2_bdpt_32.exr tiny_light
door_ajar scenes/stability/door_ajar.json door_ajar_32.exr occluded
mirror_corridor scenes/stability/mirror_corridor.json mirror_corridor_32.exr specular_view
thin_slab scenes/stability/thin_slab.json thin_slab_32.exr specular_view
grazing scenes/stability/grazing.json grazing_32.exr direct_only
EOF
}

scene_list() {
    all_scenes | grep -e "^\(${ONLY:-.*}\) "
}

# Why each method fails (or does not) on each family of scenes: family, method, one line. Written
# by hand from how the methods sample (docs/methods.md) and what the atlas measures.
why_list() {
    cat <<'EOF'
diffuse_room path no failure: every wall sees the light, and next-event estimation with MIS carries it
diffuse_room light sound; but each light vertex splats into one pixel, so a pixel gets fewer useful samples per second than path tracing gives it
diffuse_room bdpt no failure
diffuse_room sppm noisy: every pixel's light, the direct light too, comes from merging one iteration's photons within a small radius
diffuse_room vcm no failure: connections carry the room, the merge adds little
diffuse_room vcm-full no failure
diffuse_room whitted no indirect diffuse light: the box converges too dark
diffuse_room photon-map sound but slow: a sample takes a shadow ray, a gather ray and two density estimates, and the fixed radius blurs the global map's light near edges, a bias that stays
diffuse_room radiosity its home ground: the box's indirect light from the patch solution, constant per patch, blurs the corners and shadows a little (image mean 0.998)
specular_room path light that reaches the walls by way of the mirrors and glass is found only by BSDF sampling onto the light: fireflies
specular_room light the mirror wall, the mirror sphere and the glass spheres stay black: light tracing cannot reach the camera through them
specular_room bdpt sound: next-event estimation through the planar mirror and connections carry the reflected light
specular_room sppm noisy: merging carries all the light, the direct light too
specular_room vcm sound; the merges take the caustics of the glass spheres
specular_room vcm-full sound
specular_room whitted no indirect light and no caustics
specular_room photon-map the caustic map carries the light by way of the mirrors and glass, final gathering the indirect light: within 3x of vcm, blurred at the fixed radius
specular_room radiosity leaves out the light by way of the mirror wall and spheres and the glass's caustics: about 0.9 of the image mean
caustic path the caustic under the sphere is found only by floor paths whose BSDF sample refracts through the sphere onto the small light
caustic light the sphere, and the floor seen through it, stay black; the caustic seen directly is light tracing's best case
caustic bdpt the caustic comes from light tracing onto the camera; the floor seen through the sphere only from BSDF sampling, as in path
caustic sppm noisy: every pixel's light comes from merges, the directly lit floor too
caustic vcm merges find the caustic, also where the camera sees it through the sphere
caustic vcm-full as vcm
caustic whitted no caustic: the floor under the sphere is black
caustic photon-map the caustic map finds the caustic, seen directly or through the sphere, blurred by the fixed radius
caustic radiosity no caustic: rays that meet the glass are lost, so the floor under the sphere is dark
mirror_caustic path camera -> mirror -> floor -> glass -> light: only BSDF sampling through the sphere onto the small light finds the caustic
mirror_caustic light black wherever the camera looks through the mirror or the sphere: the caustic is never seen
mirror_caustic bdpt the floor seen in the mirror joins a light vertex on the same floor at zero cosine: no connection finds the caustic, only BSDF sampling as in path
mirror_caustic sppm finds the caustic in the mirror by merging, but merges all the light, the direct light too: noisy everywhere
mirror_caustic vcm merges the caustic's photons at the floor seen in the mirror; connections carry the rest
mirror_caustic vcm-full merges and connects at every diffuse vertex: slower iterations than vcm for the same caustic
mirror_caustic whitted no caustic, in the mirror or elsewhere
mirror_caustic photon-map the camera's ray through the mirror meets the floor, where the caustic map holds the caustic: within 2x of vcm
mirror_caustic radiosity no caustic, in the mirror or elsewhere
enclosed_light path every shadow ray hits the glass: next-event estimation finds nothing, and all light comes from BSDF sampling onto a tiny emitter
enclosed_light light sound in the room; the bulb, where much of the image's light is, stays black
enclosed_light bdpt light tracing and connections from light subpaths that left the glass carry the room; the emitter seen through the bulb only by BSDF sampling
enclosed_light sppm photons leave the bulb freely, but merging all the light makes it noisy
enclosed_light vcm connections and merges from light subpaths that left the glass carry the room
enclosed_light vcm-full as vcm, with slower iterations
enclosed_light whitted black room: its direct light stops at the glass and it has no caustics; only the bulb is seen
enclosed_light photon-map next-event estimation is blocked by the glass, so the room's direct light comes from the caustic map alone: found, but every pixel is a density estimate
enclosed_light radiosity the form factors' rays stop at the glass: the room gets no light at all, only the bulb is seen
tiny_light path the small light seen in the mirror wall and sphere (diffuse -> mirror -> light) only by BSDF sampling: rare, huge samples
tiny_light light the mirrors stay black; the room itself is light tracing's easy case
tiny_light bdpt next-event estimation through the planar mirror wall; the mirror sphere's reflections of the light only by BSDF sampling
tiny_light sppm merging takes the paths by way of the mirrors, but carries all the light, the direct light too: noisy
tiny_light vcm sound: merges take the paths by way of the mirror sphere
tiny_light vcm-full sound; slower iterations than vcm
tiny_light whitted no indirect light and no light by way of the mirrors
tiny_light photon-map next-event estimation takes the small light; by way of the mirrors its light comes from the caustic map, blurred
tiny_light radiosity leaves out the small light's reflections in the mirrors
occluded path from the dark room the light is occluded except along the slit's streak: camera paths must find the slit by BSDF sampling
occluded light light subpaths pass the slit as rarely as camera paths do, but every vertex beyond it connects to the camera
occluded bdpt light tracing's strategy carries the room; the other strategies cost time without passing the slit more often
occluded sppm few photons pass the slit per iteration: the merges are noisy
occluded vcm connections carry the room as in bdpt, and its shorter camera subpaths make iterations cheaper
occluded vcm-full as bdpt, with merges
occluded whitted almost black: only the streak of direct light through the slit
occluded photon-map few photons pass the slit: the dark room's light is one gather ray into a sparse global map, noisy and blurred
occluded radiosity the streak of direct light past the gap lights a whole patch's area, which then lights the dark room: 1.5x too bright at the default patch size (1.29x at half of it)
specular_view path no failure: a deterministic chain of mirror or glass bounces to the emitter
specular_view light black: the camera sees only mirrors or glass
specular_view bdpt sound; its light subpaths add nothing through specular surfaces and cost time
specular_view sppm no diffuse vertex to merge at: the light subpaths cost time for nothing
specular_view vcm as sppm
specular_view vcm-full as sppm
specular_view whitted cut after 5 specular bounces: exact through the thin slab, too dark in the mirror corridor, whose light arrives after up to 50 bounces
specular_view photon-map no diffuse vertex seen: the photon maps cost time for nothing
specular_view radiosity as whitted: its rays follow mirrors and glass to 5 specular bounces
direct_only path no failure: the plane sees only emitters, found by next-event estimation and BSDF sampling alike
direct_only light light subpaths start all over the large emitting walls and few reach the narrow view: few splats per pixel
direct_only bdpt sound; more work per sample than path for the same paths
direct_only sppm the default merge radius comes out 2.3e-4 here (a share of a narrow view 0.01 above the plane): merges find almost no photons, the plane is black but for rare huge merges; --radius 0.5 renders it well
direct_only vcm its default merge radius is tiny here too (5.9e-4): merges with few photons add noise that path tracing does not have; --radius 0.5 gives a fifth of the error
direct_only vcm-full sound; more work per sample than path
direct_only whitted exact (all light is direct), but one light sample per pixel without MIS is noisier than path tracing
direct_only photon-map all light is direct: one light sample per vertex without MIS, as whitted, with fewer samples (each also traces photons and a gather ray)
direct_only radiosity all light is direct: one light sample per vertex without MIS, as whitted
EOF
}

# The methods of the binary: the values listed under --method in `hexray render --help`.
known_methods() {
    "$hexray" render --help | sed -n '/^ *--method </,/^ *--radius </p' | sed -n 's/^ *- \([a-z-]*\): .*/\1/p'
}

have_gpu() {
    "$hexray" info 2> /dev/null | grep '^\[' > /dev/null
}

# One render of ATLAS_SECONDS and its comparison: one CSV row.
measure() {
    local name=$1 scene=$2 ref=$3 family=$4 method=$5 backend=$6
    local dir=$work/$backend/$name
    mkdir -p "$dir"
    local log=$dir/$method.log
    rm -f "$dir/$method".*  "$dir/${method}_var.exr"
    if ! "$hexray" render "$scene" --backend "$backend" --method "$method" --time "$seconds" \
        --width $size --height $size --seed $seed --variance --out "$dir/$method.exr" > "$log" 2>&1; then
        local why
        why=$(grep -m1 -i 'error' "$log" | tr ',' ';' || true)
        echo "$name,$family,$method,$backend,failed,,,,,,,${why:-the render failed: see $log}"
        return
    fi
    local line spp secs
    line=$(grep -m1 '^rendered ' "$log" || true)
    spp=$(echo "$line" | sed -n 's/^rendered \([0-9]*\) spp.*/\1/p')
    secs=$(echo "$line" | sed -n 's/.* in \([0-9.]*\) s .*/\1/p')
    # The reference's own noise: its variance against itself (a render of 1 spp has no variance
    # file, and compare then leaves this out).
    local noise
    noise=$("$hexray" compare "$refs/$ref" "$refs/$ref" --json \
        | python3 -c 'import json, sys; print(json.load(sys.stdin)["relmse_reference_noise"])')
    local json
    if ! json=$("$hexray" compare "$dir/$method.exr" "$refs/$ref" --json 2> "$dir/$method.compare.log"); then
        echo "$name,$family,$method,$backend,failed,$secs,$spp,,,,,compare failed: see $dir/$method.compare.log"
        return
    fi
    echo "$json" | python3 -c '
import json, sys
c = json.load(sys.stdin)
noise, a = float(sys.argv[1]), sys.argv[2:]
ratio = sum(c["ratio"]) / len(c["ratio"])
rel = c["relmse"]
net = rel - noise
print(",".join(a + ["%.4g" % rel, "%.3g" % noise, "%.4g" % net, "%.4f" % ratio, ""]))
' "$noise" "$name" "$family" "$method" "$backend" ok "$secs" "$spp"
}

run() {
    [ -x "$hexray" ] || { echo "no binary at $hexray: build it (cargo build --release) or set HEXRAY" >&2; exit 1; }
    local known backend_list=""
    known=" $(known_methods | tr '\n' ' ') "
    for b in $backends; do
        if [ "$b" = gpu ] && ! have_gpu; then
            echo "== no GPU adapter: gpu left out" >&2
            continue
        fi
        backend_list="$backend_list $b"
    done
    mkdir -p "$out" "$work"
    # Provenance: with ATLAS_KEEP each run adds its line (its methods, commit, date, time).
    put() { if [ -n "${ATLAS_KEEP:-}" ]; then cat >> "$1"; else cat > "$1"; fi; }
    local which=${METHODS:-all methods}
    git update-index -q --refresh > /dev/null 2>&1 || true  # stale file times are not changes
    echo "$(git describe --always --dirty 2> /dev/null) ($which)" | put "$out/commit.txt"
    echo "$(date -u +%F) ($which)" | put "$out/date.txt"
    local adapter
    adapter=$("$hexray" info 2> /dev/null | sed -n 's/^\[0\] //p' | head -1)
    echo "$(nproc) cores ($(sed -n 's/^model name\s*: //p' /proc/cpuinfo | head -1)); GPU backend on ${adapter:-no adapter}; $("$hexray" --version)" \
        > "$out/machine.txt"
    local csv=$out/results.csv start=$SECONDS
    if [ -n "${ATLAS_KEEP:-}" ] && [ -f "$csv" ]; then
        # Keep the other methods' rows; render METHODS again.
        python3 - "$csv" $methods <<'PY'
import csv, sys
path, methods = sys.argv[1], set(sys.argv[2:])
rows = list(csv.reader(open(path)))
with open(path, "w", newline="") as f:
    w = csv.writer(f, lineterminator="\n")
    w.writerow(rows[0])
    w.writerows(r for r in rows[1:] if r[2] not in methods)
PY
    else
        echo "scene,family,method,backend,status,seconds,spp,relmse,relmse_reference_noise,relmse_net,mean_ratio,note" > "$csv"
    fi
    scene_list | while read -r name scene ref family; do
        [ -f "$refs/$ref" ] || { echo "missing $refs/$ref: run docs/figures/stability.sh references" >&2; exit 1; }
        for b in $backend_list; do
            for m in $methods; do
                case "$known" in
                    *" $m "*)
                        echo "== $name $m $b" >&2
                        # Warm-up: lavapipe compiles each kernel once per scene layout (then
                        # from its disk cache); the timed render should not pay for that.
                        if [ "$b" = gpu ]; then
                            "$hexray" render "$scene" --backend gpu --method "$m" --spp 1 \
                                --width 8 --height 8 --out "$work/warmup.exr" --quiet > /dev/null 2>&1 || true
                        fi
                        measure "$name" "$scene" "$ref" "$family" "$m" "$b" >> "$csv" ;;
                    *) echo "$name,$family,$m,$b,skipped,,,,,,,not in $("$hexray" --version)" >> "$csv" ;;
                esac
            done
        done
    done
    echo "run time $((SECONDS - start)) s ($seconds s per render; $which)" | tee /dev/stderr | put "$out/runtime.txt"
    montage
    markdown
}

# A picture grid per backend: one row per scene (the reference first, then METHODS in order),
# each 32x32 render shown 3x; a cell is grey where the method was skipped or failed. Python's
# standard library only (zlib): hexray writes 8-bit RGB PNGs.
montage() {
    local b
    for b in cpu gpu; do
        grep -q ",$b," "$out/results.csv" || continue
        python3 - "$out/results.csv" "$b" "$work" "$refs" "$out/montage_$b.png" $all_methods <<'PY'
import csv, os, struct, sys, zlib
path, backend, work, refs, dest, methods = sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4], sys.argv[5], sys.argv[6:]
rows = [r for r in csv.DictReader(open(path)) if r["backend"] == backend]
scenes = list(dict.fromkeys(r["scene"] for r in rows))
ok = {(r["scene"], r["method"]) for r in rows if r["status"] == "ok"}
ref_of = {}
for line in os.popen("bash docs/atlas.sh scenes"):
    n, _, ref, _ = line.split()
    ref_of[n] = ref

def read_png(p):
    d = open(p, "rb").read()
    i, idat, w, h = 8, b"", 0, 0
    while i < len(d):
        n, = struct.unpack(">I", d[i:i + 4]); t = d[i + 4:i + 8]; c = d[i + 8:i + 8 + n]
        if t == b"IHDR":
            w, h, depth, ctype, _, _, lace = struct.unpack(">IIBBBBB", c)
            assert depth == 8 and ctype == 2 and lace == 0, p
        elif t == b"IDAT":
            idat += c
        i += 12 + n
    raw, stride, out, prev = zlib.decompress(idat), 3 * w, [], bytearray(3 * w)
    for y in range(h):
        f, line = raw[y * (stride + 1)], bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for x in range(stride):
            a = line[x - 3] if x >= 3 else 0
            b, c = prev[x], prev[x - 3] if x >= 3 else 0
            if f == 1: line[x] = (line[x] + a) & 255
            elif f == 2: line[x] = (line[x] + b) & 255
            elif f == 3: line[x] = (line[x] + (a + b) // 2) & 255
            elif f == 4:
                p_ = a + b - c; pa, pb, pc = abs(p_ - a), abs(p_ - b), abs(p_ - c)
                line[x] = (line[x] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        out.append(line); prev = line
    return w, h, out

S, G = 3, 2  # scale, gap
cell = 32 * S
cols = ["reference"] + methods
W, H = len(cols) * (cell + G) + G, len(scenes) * (cell + G) + G
img = [bytearray([40, 40, 40] * W) for _ in range(H)]
for i, s in enumerate(scenes):
    for j, m in enumerate(cols):
        p = os.path.join(refs, ref_of[s].replace(".exr", ".png")) if m == "reference" else os.path.join(work, backend, s, m + ".png")
        x0, y0 = G + j * (cell + G), G + i * (cell + G)
        if m != "reference" and (s, m) not in ok or not os.path.exists(p):
            for y in range(cell):
                img[y0 + y][3 * x0:3 * (x0 + cell)] = bytearray([110, 110, 110] * cell)
            continue
        w, h, px = read_png(p)
        for y in range(cell):
            src = px[y * h // cell]
            img[y0 + y][3 * x0:3 * (x0 + cell)] = bytearray(b for x in range(cell) for b in src[3 * (x * w // cell):3 * (x * w // cell) + 3])
def chunk(t, c):
    return struct.pack(">I", len(c)) + t + c + struct.pack(">I", zlib.crc32(t + c) & 0xffffffff)
data = b"".join(b"\x00" + bytes(r) for r in img)
open(dest, "wb").write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", W, H, 8, 2, 0, 0, 0))
                      + chunk(b"IDAT", zlib.compress(data, 9)) + chunk(b"IEND", b""))
print("wrote", dest)
PY
    done
}

# The generated part of docs/atlas.md (between its "begin generated" and "end generated" lines)
# from docs/figures/atlas/results.csv and the why lines above; the text around it is written by
# hand and kept as it is.
markdown() {
    local block=$out/generated.md.tmp
    mkdir -p "$out"
    python3 - "$out" "$seconds" <(why_list) <(all_scenes) $all_methods <<'PY' > "$block"
import csv, os, sys
out, budget, why_path, scenes_path, methods = sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4], sys.argv[5:]
why = {}
for line in open(why_path):
    fam, m, text = line.rstrip("\n").split(" ", 2)
    why[(fam, m)] = text
scenes = [l.split() for l in open(scenes_path) if l.strip()]
family = {s[0]: s[3] for s in scenes}
p = os.path.join(out, "results.csv")
rows = list(csv.DictReader(open(p))) if os.path.exists(p) else []
rel = "figures/atlas"
def meta(name):
    f = os.path.join(out, name)
    return "; ".join(open(f).read().split("\n")).strip("; ") if os.path.exists(f) else None
print("<!-- begin generated by docs/atlas.sh markdown: edit the script, not this part -->")
print()
if not rows:
    print("No results yet: `docs/atlas.sh run` writes them (docs/figures/atlas/results.csv).")
    print()
else:
    with open(os.path.join(out, "best.csv"), "w") as f:
        f.write("scene,backend,best_method,relmse_net,second_method,second_over_best\n")
        for backend in ("cpu", "gpu"):
            for s in dict.fromkeys(r["scene"] for r in rows):
                got = sorted((float(r["relmse_net"]), r["method"]) for r in rows
                             if r["scene"] == s and r["backend"] == backend and r["status"] == "ok")
                if got:
                    second = got[1] if len(got) > 1 else (float("nan"), "")
                    f.write(f"{s},{backend},{got[0][1]},{got[0][0]:.4g},{second[1]},"
                            f"{second[0] / max(got[0][0], 1e-12):.3g}\n")
    print(f"32x32 renders of {budget} s each (seed 11) against the references in "
          "`tests/data/references/stability/`; relMSE minus the reference's own noise. "
          f"How this was measured: `docs/atlas.sh run`"
          + (f", on {meta('machine.txt')}" if meta("machine.txt") else "")
          + (f"; on {meta('date.txt')}" if meta("date.txt") else "")
          + (f"; commit {meta('commit.txt')}" if meta("commit.txt") else "")
          + (f"; {meta('runtime.txt')}" if meta("runtime.txt") else "") + ".")
    print()
    for backend in ("cpu", "gpu"):
        br = [r for r in rows if r["backend"] == backend]
        if not br:
            continue
        cols = [m for m in methods if any(r["method"] == m and r["status"] == "ok" for r in br)]
        absent = [m for m in methods if m not in cols]
        print(f"## {backend.upper()}")
        print()
        print("Each cell: relMSE (its ratio to the scene's best). Best in bold.")
        print()
        print("| scene | " + " | ".join(f"`{m}`" for m in cols) + " | best |")
        print("| --- |" + " --- |" * (len(cols) + 1))
        for s in dict.fromkeys(r["scene"] for r in br):
            got = {r["method"]: r for r in br if r["scene"] == s and r["status"] == "ok"}
            if not got:
                continue
            net = {m: float(got[m]["relmse_net"]) for m in got}
            best = min(net, key=net.get)
            floor = max(net[best], 1e-12)
            cells = []
            for m in cols:
                if m not in got:
                    cells.append("–")
                    continue
                r = net[m] / floor
                c = f"{net[m]:.2e} (×{r:.2f})" if r < 10 else f"{net[m]:.2e} (×{r:.3g})"
                cells.append(f"**{c}**" if m == best else c)
            print(f"| {s} | " + " | ".join(cells) + f" | `{best}` |")
        print()
        notes = sorted({(r["method"], r["status"], r["note"]) for r in br if r["status"] != "ok"})
        for m, st, note in notes:
            print(f"- `{m}`: {st} ({note})")
        if notes:
            print()
        print(f"Samples per pixel and image-mean ratio to the reference (a ratio far from 1 is bias"
              f" or missing light):")
        print()
        print("| scene | " + " | ".join(f"`{m}`" for m in cols) + " |")
        print("| --- |" + " --- |" * len(cols))
        for s in dict.fromkeys(r["scene"] for r in br):
            got = {r["method"]: r for r in br if r["scene"] == s and r["status"] == "ok"}
            if got:
                print(f"| {s} | " + " | ".join(f"{got[m]['spp']} spp, {float(got[m]['mean_ratio']):.3f}"
                                                  if m in got else "–" for m in cols) + " |")
        print()
        if os.path.exists(os.path.join(out, f"montage_{backend}.png")):
            print(f"![{backend} renders of every scene and method]({rel}/montage_{backend}.png)")
            print()
            print("Rows: " + ", ".join(dict.fromkeys(r["scene"] for r in br)) + ". Columns: the reference, "
                  + ", ".join(methods) + " (grey: skipped or failed).")
            print()
print("## Why each method fails there")
print()
print("By family of scenes; written by hand in docs/atlas.sh (`why_list`). A dash: not written yet.")
print()
for fam in dict.fromkeys(s[3] for s in scenes):
    names = ", ".join(s[0] for s in scenes if s[3] == fam)
    print(f"**{fam}** ({names})")
    print()
    for m in methods:
        print(f"- `{m}`: {why.get((fam, m), '–')}")
    print()
print("<!-- end generated -->")
PY
    python3 - "$block" docs/atlas.md <<'PY'
import sys
block, page = open(sys.argv[1]).read(), sys.argv[2]
text = open(page).read()
begin, end = "<!-- begin generated", "<!-- end generated -->"
i, j = text.index(begin), text.index(end) + len(end)
open(page + ".tmp", "w").write(text[:i] + block.rstrip("\n") + text[j:])
PY
    mv docs/atlas.md.tmp docs/atlas.md
    rm -f "$block"
    echo "wrote docs/atlas.md"
}

case "${1:-}" in
    run) run ;;
    markdown) markdown ;;
    montage) montage ;;
    scenes) all_scenes ;;
    *) echo "usage: docs/atlas.sh run|markdown|montage|scenes" >&2; exit 2 ;;
esac
