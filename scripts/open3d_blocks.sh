#!/usr/bin/env bash
# Building blocks against Open3D (issue 17): back-projection, kd-tree build, kNN-30 normals, a
# RANSAC plane and a voxel grid, timed single-threaded on the same depth frame in Pomona and in
# Open3D 0.20.0, with the ratio Pomona / Open3D per block.
#
#   scripts/open3d_blocks.sh [OUT]          (default OUT: /tmp/pomona-open3d-blocks)
#
# Frames: a synthetic Kinect v2 `wide` frame (`pomona synth --seed 17`, frame 000000), and the real
# Azure Kinect orchard frame ../shared/data/ak-apples/121804 when that folder is present (skipped
# with a message otherwise). Installs Open3D from PyPI into a venv under the cargo target folder
# (with `libusb-package`, which provides the libusb-1.0 that Open3D's wheel links against).
# Threads: Pomona runs inside a one-thread rayon pool (and RAYON_NUM_THREADS=1), Open3D after
# o3d.utility.set_max_threads(1) (its oneTBB ignores OMP_NUM_THREADS; set as well). The two sides alternate ROUNDS times (default 3), so both see the same machine
# load; each round times every block REPEATS times (default 15) after a warm-up, and the table
# gives the median over rounds of those medians.
# POMONA_BLOCKS=/path/to/open3d_blocks times that build of Pomona's example instead (e.g. an older
# commit's, for a before/after table). Prints Markdown tables and writes them to OUT/table.md.
set -euo pipefail
cd "$(dirname "$0")/.."
OUT=${1:-/tmp/pomona-open3d-blocks}
REPEATS=${REPEATS:-15}
ROUNDS=${ROUNDS:-3}
TARGET=${CARGO_TARGET_DIR:-$(pwd)/target}
VENV="$TARGET/open3d-venv"
mkdir -p "$OUT"

if ! "$VENV/bin/python" -c 'import numpy, libusb_package' 2> /dev/null \
  || [ "$("$VENV/bin/pip" show open3d 2> /dev/null | sed -n 's/^Version: //p')" != "0.20.0" ]; then
  echo "installing open3d 0.20.0 into $VENV" >&2
  python3 -m venv "$VENV"
  "$VENV/bin/pip" install -q open3d==0.20.0 numpy libusb-package
fi
# Open3D's wheel needs libusb-1.0.so.0 (for its Azure Kinect reader); take it from the venv.
USB_DIR="$VENV/libusb"
mkdir -p "$USB_DIR"
ln -sf "$("$VENV/bin/python" -c 'import libusb_package, pathlib; print(pathlib.Path(libusb_package.__file__).parent / "libusb-1.0.so")')" \
  "$USB_DIR/libusb-1.0.so.0"

cargo build --release -q -p pomona-cli -p pomona-consensus --example open3d_blocks
POMONA="$TARGET/release/pomona"
BLOCKS=${POMONA_BLOCKS:-$TARGET/release/examples/open3d_blocks}

SYNTH="$OUT/synth-kinect-v2-wide"
if [ ! -f "$SYNTH/depth/000000.png" ]; then
  "$POMONA" synth --out "$SYNTH" --frames 1 --seed 17 --camera kinect-v2 --domain wide --force > /dev/null
fi
FRAMES=("synthetic Kinect v2 wide, seed 17|$SYNTH|000000")
AK=../shared/data/ak-apples
if [ -f "$AK/depth/121804.png" ]; then
  FRAMES+=("real Azure Kinect orchard (ak-apples)|$AK|121804")
else
  echo "skipping the Azure Kinect frame: $AK/depth/121804.png is absent" >&2
fi

: > "$OUT/table.md"
i=0
for f in "${FRAMES[@]}"; do
  IFS='|' read -r label data frame <<< "$f"
  i=$((i + 1))
  POMONA_RUNS=()
  OPEN3D_RUNS=()
  for r in $(seq 1 "$ROUNDS"); do
    RAYON_NUM_THREADS=1 "$BLOCKS" --data "$data" --frame "$frame" --repeats "$REPEATS" \
      > "$OUT/pomona-$i-$r.json"
    LD_LIBRARY_PATH="$USB_DIR${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}" OMP_NUM_THREADS=1 \
      "$VENV/bin/python" scripts/open3d_blocks.py measure --data "$data" --frame "$frame" \
      --repeats "$REPEATS" > "$OUT/open3d-$i-$r.json"
    POMONA_RUNS+=("$OUT/pomona-$i-$r.json")
    OPEN3D_RUNS+=("$OUT/open3d-$i-$r.json")
  done
  "$VENV/bin/python" scripts/open3d_blocks.py table --label "$label" --frame "$frame" \
    --repeats "$REPEATS" --pomona-json "${POMONA_RUNS[@]}" --open3d-json "${OPEN3D_RUNS[@]}" \
    --out "$OUT/table-$i.md"
  cat "$OUT/table-$i.md" >> "$OUT/table.md"
done
echo "load while timing: $(uptime)" | tee -a "$OUT/table.md"
