#!/usr/bin/env bash
# The confidence calibration of the built-in shape-fit model (crates/pomona-shapefit/models/
# default.json): the score and the detections' geometric cues (`pomona calibrate --cues`),
# fitted on 16 sets of our generator's `wide` and `narrow` frames (seeds 701-705, 711-715; never
# used for training, tuning or testing), the composition of scripts/wide_builtin_eval.sh's sets.
# The classifier and stage parameters stay as trained; only `calibration` changes.
#
#   scripts/calibrate_builtin_shapefit.sh [WORKDIR]      (writes the model in place)
#
# POMONA=/path/to/pomona uses that binary instead of building one. Same seeds, same bytes.
set -euo pipefail
cd "$(dirname "$0")/.."
WORK=${1:-/tmp/pomona-calibrate-shapefit}
if [ -z "${POMONA:-}" ]; then
  cargo build --release -q -p pomona-cli
  POMONA=$(pwd)/target/release/pomona
fi
mkdir -p "$WORK"
DATA=()
for batch in 700 710; do
  while read -r name seed args; do
    seed=$((seed - 500 + batch))
    dir="$WORK/$name-$batch"
    # shellcheck disable=SC2086
    [ -f "$dir/camera.json" ] || "$POMONA" synth --out "$dir" --frames 10 --seed "$seed" $args --force > /dev/null
    DATA+=(--data "$dir")
  done <<'SETS'
pepper 501 --fruit pepper
eggplant 501 --fruit eggplant
guava 501 --fruit guava
apple 501 --fruit apple
orange 501 --fruit orange
mixed-d435 503 --fruit mixed --camera d435
pepper-sr4000 504 --fruit pepper --camera sr4000
narrow-mixed 505 --fruit mixed --domain narrow --noise tof
SETS
done
MODEL=crates/pomona-shapefit/models/default.json
"$POMONA" calibrate --pipeline shape-fit --model "$MODEL" "${DATA[@]}" --cues --out "$WORK/default.json"
cp "$WORK/default.json" "$MODEL"
