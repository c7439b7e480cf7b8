#!/usr/bin/env bash
# Runs this tree's command-line tests against the hexray binary of another commit (default:
# 7d8d6b7, where issue 16's cases were observed), to show which tests fail there and pass here.
#
#   tests/against_build.sh [COMMIT] [TEST FILTER ...]
#
# The old commit is built in a git worktree under target/against/ (a cold release build, about
# 4.5 minutes on 2 cores). Tests that call the library rather than the binary run this tree's
# code either way, so only the command-line tests say anything about the old build.
set -euo pipefail
cd "$(dirname "$0")/.."
commit=${1:-7d8d6b7}
shift || true
filters=("$@")
[ ${#filters[@]} -eq 0 ] && filters=(nothing_lost crafted_files bad_input cli:: merge:: compare:: gpu_bands meshes::)
tree=target/against/$commit
if [ ! -x "$tree/target/release/hexray" ]; then
    rm -rf "$tree"
    git worktree prune
    git worktree add -f -q "$tree" "$commit"
    (cd "$tree" && cargo build --release --bin hexray)
fi
cargo test --release --test tests --no-run
for build in this "$commit"; do
    if [ "$build" = this ]; then unset HEXRAY_UNDER_TEST; else export HEXRAY_UNDER_TEST=$PWD/$tree/target/release/hexray; fi
    echo "== $build"
    cargo test --release --test tests -- "${filters[@]}" 2>&1 |
        grep -E '^test .* \.\.\. (ok|FAILED)$|^test result' | sort > "target/against/$build.txt" || true
    grep -c ' ok$' "target/against/$build.txt" | sed 's/^/passed: /'
    grep -c 'FAILED$' "target/against/$build.txt" | sed 's/^/failed: /' || true
done
echo "== failing with $commit, passing with this tree:"
join <(grep 'FAILED$' "target/against/$commit.txt" | awk '{print $2}' | sort) \
     <(grep ' ok$' target/against/this.txt | awk '{print $2}' | sort)
