#!/usr/bin/env bash
# Prepares, on this machine, everything benches/lent_gpu.sh needs on a lent GPU, which builds
# nothing there and reaches no network:
#   .devbin/bin.tar.xz   hexray, the integration tests (`cargo test --release --no-run`) and a
#                        `--features stage-times` build, stripped;
#   .devbin/mi/          Mitsuba 3.9.1 trimmed to cuda_ad_rgb (../shared/mitsuba/gpu/make_mi_trim.sh;
#                        WITH_LLVM=1 adds llvm_ad_rgb for lent_gpu.sh's DRY_RUN) with its timing
#                        script and scene converter;
#   .gl/                 the Vulkan loader's packages (the lent machine has the driver only).
# Both folders are ignored through .git/info/exclude, and the call carries them:
#
#   benches/lent_gpu_prepare.sh
#   run(command="bash benches/lent_gpu.sh", carry=[".gl", ".devbin"], timeout_s=590)
#
# The tree and the carried folders must stay under the device's 64 MiB; the script says where
# they stand. Needs the network once (pip download, apt-get download). About 15 minutes on
# 2 cores, most of it the two release builds.
set -euo pipefail
cd "$(dirname "$0")/.."
shared=${SHARED:-../shared/mitsuba}
for p in /.devbin/ /.gl/; do
    grep -qxF "$p" .git/info/exclude 2>/dev/null || echo "$p" >> .git/info/exclude
done
mkdir -p .devbin/mi .gl
bin=$(mktemp -d)

echo "== hexray and the integration tests"
cargo build --release
strip -o "$bin/hexray" target/release/hexray
tests=$(cargo test --release --no-run 2>&1 | sed -n 's/.*Executable tests\/main.rs (\(.*\))/\1/p' | tail -1)
[ -n "$tests" ] || { echo "no test binary found" >&2; exit 1; }
strip -o "$bin/tests" "$tests"
if [ "${STAGES:-1}" = 1 ]; then
    echo "== the stage-times build"
    cargo build --release --features stage-times --target-dir target/stage-times
    strip -o "$bin/hexray-stages" target/stage-times/release/hexray
fi
tar -C "$bin" -cf - . | xz -9 -T2 > .devbin/bin.tar.xz
rm -rf "$bin"

echo "== Mitsuba"
if [ ! -f .devbin/mi/mi_trim.tar.xz ]; then
    sh "$shared/gpu/make_mi_trim.sh" out/mi_work
    cp out/mi_work/mi_trim.tar.xz .devbin/mi/
fi
cp "$shared/gpu/mi_gpu_bench.py" "$shared/scene_to_mitsuba.py" .devbin/mi/

echo "== the Vulkan loader"
if ! ls .gl/*.deb > /dev/null 2>&1; then
    o='-oAPT::Architecture=amd64 -oAPT::Architectures=amd64 -oDir::State::Lists=/tmp/amd64'
    mkdir -p /tmp/amd64/partial
    # shellcheck disable=SC2086
    apt-get $o update > /dev/null
    # shellcheck disable=SC2086
    (cd .gl && apt-get $o download libvulkan1)
fi

tree=$(git ls-files -z | xargs -0 du -cb 2>/dev/null | tail -1 | cut -f1)
carried=$(du -cb .devbin .gl | tail -1 | cut -f1)
echo "tree $((tree >> 20)) MiB + carried $((carried >> 20)) MiB = $(((tree + carried) >> 20)) MiB (limit 64)"
[ $((tree + carried)) -le $((64 << 20)) ] || { echo "over the device's 64 MiB" >&2; exit 1; }
