#!/usr/bin/env bash
# Seconds from Ctrl-C (SIGINT) to the end of a render, the signal sent at a fixed time after
# the render's start: how long a first Ctrl-C waits for the work under way.
#
#   benches/stop_latency.sh                          # CPU, vcm, 1024x1024, signal at 5 s
#   BACKEND=gpu SIZE=2048 AFTER=20 ROUNDS=3 benches/stop_latency.sh
#
# HEXRAY (default target/release/hexray), METHOD (vcm), SCENE (scenes/cornell_box.json), SIZE
# (1024), BACKEND (cpu), AFTER (seconds from the start to the signal, 5: past the set-up),
# ROUNDS (3). Prints one row per round: the latency, the exit status, and the samples kept.
set -euo pipefail
cd "$(dirname "$0")/.."
hexray=${HEXRAY:-target/release/hexray}
size=${SIZE:-1024}
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
echo "backend method size after_s latency_s status spp_kept"
for r in $(seq "${ROUNDS:-3}"); do
    "$hexray" render "${SCENE:-scenes/cornell_box.json}" --backend "${BACKEND:-cpu}" \
        --method "${METHOD:-vcm}" --width "$size" --height "$size" --time 3600 -q \
        --out "$out/s$r.exr" 2> "$out/log$r" &
    pid=$!
    sleep "${AFTER:-5}"
    t0=$(date +%s.%N)
    kill -INT "$pid"
    status=0
    wait "$pid" || status=$?
    t1=$(date +%s.%N)
    spp=$(python3 - "$out/s$r.film" <<'PY'
import json, os, sys
p = sys.argv[1]
if not os.path.exists(p):
    print(0)
else:
    head = open(p, "rb").read(65536)
    start = head.index(b"{")
    depth = 0
    for i, c in enumerate(head[start:]):
        depth += c == ord("{")
        depth -= c == ord("}")
        if depth == 0:
            print(json.loads(head[start:start + i + 1])["spp"])
            break
PY
)
    echo "${BACKEND:-cpu} ${METHOD:-vcm} $size ${AFTER:-5} $(python3 -c "print(f'{$t1 - $t0:.2f}')") $status $spp"
done
