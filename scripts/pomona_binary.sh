# Sourced (`. scripts/pomona_binary.sh`) by the reproduction scripts, from the repository root:
# sets POMONA to the `pomona` binary they drive — the one the caller named in $POMONA, else this
# checkout's release build, built first. POSIX sh, so the sh and bash scripts share it.
if [ -z "${POMONA:-}" ]; then
  cargo build --release -q -p pomona-cli
  POMONA=$(pwd)/target/release/pomona
fi
