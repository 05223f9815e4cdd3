#!/usr/bin/env bash
# The Python package's tests, run the way a user installs it: a virtual environment under
# target/ (or $POMONA_PY_VENV), `pip install "./crates/pomona-py[test]"` (maturin, numpy, pytest
# and dask[distributed] come from PyPI; the extension is built from this checkout), then pytest
# with the `pomona` binary of this checkout to compare against. scripts/test.sh runs it; extra
# arguments go to pytest.
set -euo pipefail
cd "$(dirname "$0")/.."

venv="${POMONA_PY_VENV:-target/py-venv}"
if [ ! -x "$venv/bin/python" ]; then
  python3 -m venv "$venv"
fi
"$venv/bin/python" -m pip install --quiet --disable-pip-version-check --upgrade pip
# The dev profile (a cdylib cannot be built with `--profile test`, which makes a test harness):
# quick to compile; a user's plain install builds release.
export MATURIN_PEP517_ARGS="${MATURIN_PEP517_ARGS:---profile dev}"
pip=("$venv/bin/python" -m pip install --quiet --disable-pip-version-check)
"${pip[@]}" "./crates/pomona-py[test]"
# pip keeps an installed package of the same version: reinstall this checkout's build.
"${pip[@]}" --force-reinstall --no-deps "./crates/pomona-py"

if [ -z "${POMONA_BIN:-}" ]; then
  # The test profile (target/debug, or $CARGO_TARGET_DIR/debug): what `cargo test` built already.
  cargo build --locked --profile test -p pomona-cli --bin pomona
  export POMONA_BIN="${CARGO_TARGET_DIR:-$PWD/target}/debug/pomona"
fi
exec "$venv/bin/python" -m pytest crates/pomona-py/tests "$@"
