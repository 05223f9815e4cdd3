#!/usr/bin/env bash
# Runs every fuzz target for SECONDS (default 600) one after another with one job each, growing
# a working corpus outside the repository (FUZZ_WORK, default /tmp/pomona-fuzz) seeded from
# corpus/<target>/, and keeps going past a crash (fork mode) so each target gets its full time;
# crash, timeout and out-of-memory inputs land in $FUZZ_WORK/artifacts/<target>/.
# Logs: $FUZZ_WORK/logs/<target>.log (the last "#N ... cov: C" line holds the executions and the
# coverage). Usage: fuzz/run_all.sh [SECONDS] [TARGET...]
set -euo pipefail
cd "$(dirname "$0")"
seconds=${1:-600}
shift || true
work=${FUZZ_WORK:-/tmp/pomona-fuzz}
targets=("$@")
if [ ${#targets[@]} -eq 0 ]; then
    mapfile -t targets < <(cargo +nightly fuzz list)
fi
for target in "${targets[@]}"; do
    max_len=4096
    [ "$target" = dataset ] && max_len=16384
    mkdir -p "$work/corpus/$target" "$work/artifacts/$target" "$work/logs"
    echo "== $target: ${seconds}s, max_len $max_len"
    cargo +nightly fuzz run "$target" "$work/corpus/$target" "corpus/$target" -- \
        -max_total_time="$seconds" -rss_limit_mb=2048 -malloc_limit_mb=2048 -timeout=10 \
        -max_len="$max_len" -fork=1 -ignore_crashes=1 -ignore_ooms=1 -ignore_timeouts=1 \
        -artifact_prefix="$work/artifacts/$target/" >"$work/logs/$target.log" 2>&1 || true
    grep -E '^#[0-9]+' "$work/logs/$target.log" | tail -n 1
    ls "$work/artifacts/$target"
done
