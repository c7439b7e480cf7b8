#!/usr/bin/env bash
# BVH build time and memory, and the cost of a camera path, as the triangle count grows: the
# room of scenes/perf/bunny_room_1m.json with the bunny cut into about 10^5, 10^6 and 10^7
# triangles (scenes/models/make_large_mesh.py with n = 5, 17, 53; generated into the ignored
# scenes/models/generated/ when missing, with their scene files beside them).
#
#   benches/mesh_scaling.sh             # build time, nodes, memory, peak RSS at each size
#   RENDER=1 benches/mesh_scaling.sh    # also `hexray bench` (CPU, path, 256x256, SPP) of each
#
# `hexray info` builds each backend's BVH the way a render does (all cores: THREADS, default 2)
# and reports the builds' seconds and the scene's memory on each; the peak resident size is the
# whole process's, which holds both.
set -euo pipefail
cd "$(dirname "$0")/.."
hexray=${HEXRAY:-target/release/hexray}
threads=${THREADS:-2}
spp=${SPP:-16}
gen=scenes/models/generated
mkdir -p "$gen"

echo "# $(date -u +%Y-%m-%dT%H:%MZ), $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs), $(nproc) cores, $threads threads; hexray $(git rev-parse --short HEAD)"
echo "triangles,bvh_build_seconds,four_wide_nodes,gpu_bvh_build_seconds,gpu_four_wide_nodes,cpu_memory_mib,gpu_memory_mib,peak_rss_mib,m_paths_per_second"
for n in 5 17 53; do
    ply="$gen/bunny_n$n.ply"
    scene="$gen/bunny_room_n$n.json"
    [ -f "$ply" ] || python3 scenes/models/make_large_mesh.py --n "$n" --out "$ply" > /dev/null
    # The scene of bunny_room_1m.json with this mesh (paths in a scene are relative to its file).
    python3 - scenes/perf/bunny_room_1m.json "$scene" "bunny_n$n.ply" <<'PY'
import json, sys
scene = json.load(open(sys.argv[1]))
scene["name"] = sys.argv[2].rsplit("/", 1)[-1][:-5]
scene["meshes"][0]["file"] = sys.argv[3]
json.dump(scene, open(sys.argv[2], "w"), indent=1)
PY
    info=$(RAYON_NUM_THREADS=$threads /usr/bin/time -f "peak_rss_kib %M" "$hexray" info "$scene" 2>&1)
    tris=$(grep -m1 '^triangles:' <<< "$info" | awk '{print $2}')
    # "bvh cpu: N four-wide nodes (M eight-wide), depth D, P prims entries, built in S s"
    build=$(grep -m1 '^bvh cpu:' <<< "$info" | awk '{print $(NF-1)}')
    nodes=$(grep -m1 '^bvh cpu:' <<< "$info" | awk '{print $3}')
    gpu_build=$(grep -m1 '^bvh gpu:' <<< "$info" | awk '{print $(NF-1)}')
    gpu_nodes=$(grep -m1 '^bvh gpu:' <<< "$info" | awk '{print $3}')
    mem=$(grep -m1 '^memory cpu:' <<< "$info" | awk '{print $3}')
    gpu_mem=$(grep -m1 '^memory gpu:' <<< "$info" | awk '{print $3}')
    rss=$(grep -m1 '^peak_rss_kib' <<< "$info" | awk '{printf "%.0f", $2 / 1024}')
    rate=""
    if [ "${RENDER:-0}" = 1 ]; then
        rate=$("$hexray" bench "$scene" --backend cpu --method path --spp "$spp" \
            --threads "$threads" --out /dev/null 2>&1 | awk '$2 == "cpu" {print $8}')
    fi
    echo "$tris,$build,$nodes,$gpu_build,$gpu_nodes,$mem,$gpu_mem,$rss,$rate"
done
