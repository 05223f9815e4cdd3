#!/usr/bin/env bash
# The project's test command: `cargo test --workspace --locked` (extra arguments are passed on),
# then the Python package's pytest suite (scripts/py-test.sh: a venv under target/, pip install
# ./crates/pomona-py), then a count of the real-data tests that skipped because ../shared/data is
# absent, so a skip is never mistaken for a pass. With POMONA_REQUIRE_DATA=1 such tests fail
# instead of skipping. The recording tests of pomona-cli's `rerun` feature (`detect --rrd`, off by
# default) run too; building that feature adds ~340 crates (about 28 min on 2 cores, once).
set -euo pipefail
cd "$(dirname "$0")/.."

skip_log="$(mktemp)"
trap 'rm -f "$skip_log"' EXIT
export POMONA_SKIP_LOG="$skip_log"

cargo test --workspace --locked "$@"
cargo test -p pomona-cli --features rerun --locked --test cli "$@" -- rrd
scripts/py-test.sh

skipped=$(wc -l <"$skip_log")
if [ "$skipped" -gt 0 ]; then
  echo "NOTE: $skipped real-data test case(s) SKIPPED (no ../shared/data; set POMONA_REQUIRE_DATA=1 to fail instead):"
  sort "$skip_log" | uniq -c
else
  echo "real-data tests: none skipped"
fi
