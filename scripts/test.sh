#!/usr/bin/env bash
# The project's test command: `cargo test --workspace --locked` (extra arguments are passed on),
# then the Python package's pytest suite (scripts/py-test.sh: a venv under target/, pip install
# ./crates/pomona-py), then a count of the real-data tests that skipped because ../shared/data is
# absent, so a skip is never mistaken for a pass. With POMONA_REQUIRE_DATA=1 such tests fail
# instead of skipping. (The `rerun` feature of pomona-cli, `detect --rrd`, is not built here:
# see crates/pomona-cli/Cargo.toml.)
set -euo pipefail
cd "$(dirname "$0")/.."

skip_log="$(mktemp)"
trap 'rm -f "$skip_log"' EXIT
export POMONA_SKIP_LOG="$skip_log"

cargo test --workspace --locked "$@"
scripts/py-test.sh

skipped=$(wc -l <"$skip_log")
if [ "$skipped" -gt 0 ]; then
  echo "NOTE: $skipped real-data test case(s) SKIPPED (no ../shared/data; set POMONA_REQUIRE_DATA=1 to fail instead):"
  sort "$skip_log" | uniq -c
else
  echo "real-data tests: none skipped"
fi
