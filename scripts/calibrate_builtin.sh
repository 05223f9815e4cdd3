#!/usr/bin/env bash
# The confidence calibration of the built-in models: the score and the detections' geometric
# cues (`pomona calibrate --cues`), fitted on 16 sets of our generator's `wide` and `narrow`
# frames (seeds 701-705, 711-715; never used for training, tuning or testing), the composition
# of scripts/wide_sets.txt, as the held-out sets of scripts/wide_builtin_eval.sh. shape-fit's
# depth-only model is fitted on the same frames without their colour images (views of symbolic
# links). Each model's classifier and stage parameters stay as trained; only its `calibration`
# changes.
#
#   scripts/calibrate_builtin.sh [WORKDIR] [PIPELINE...]   (default: shape-fit symmetry viewer-pose;
#                                                           writes the models in place)
#
# POMONA=/path/to/pomona uses that binary instead of building one. Same seeds, same bytes.
set -euo pipefail
cd "$(dirname "$0")/.."
WORK=${1:-/tmp/pomona-calibrate-builtin}
shift || true
PIPELINES=("$@")
[ ${#PIPELINES[@]} -gt 0 ] || PIPELINES=(shape-fit symmetry viewer-pose)
. scripts/pomona_binary.sh
mkdir -p "$WORK"
DATA=()
DEPTH_DATA=()
for batch in 700 710; do
  while read -r name seed args; do
    seed=$((seed - 500 + batch))
    dir="$WORK/$name-$batch"
    # shellcheck disable=SC2086
    [ -f "$dir/camera.json" ] || "$POMONA" synth --out "$dir" --frames 10 --seed "$seed" $args --force > /dev/null
    DATA+=(--data "$dir")
    # The same frames without colour: what the depth-only model detects on.
    view="$dir-depth-only"
    mkdir -p "$view"
    for part in camera.json depth truth; do
      ln -sfn "$(cd "$dir" && pwd)/$part" "$view/$part"
    done
    DEPTH_DATA+=(--data "$view")
  done < <(grep -v '^#' scripts/wide_sets.txt)
done

# calibrate PIPELINE MODEL NAME DATA...: refits MODEL's calibration in place.
calibrate() {
  local pipeline=$1 model=$2 name=$3
  shift 3
  "$POMONA" calibrate --pipeline "$pipeline" --model "$model" "$@" --cues --out "$WORK/$name.json"
  cp "$WORK/$name.json" "$model"
}
for pipeline in "${PIPELINES[@]}"; do
  case "$pipeline" in
    shape-fit)
      calibrate shape-fit crates/pomona-shapefit/models/default.json shape-fit "${DATA[@]}"
      calibrate shape-fit crates/pomona-shapefit/models/default-depth.json shape-fit-depth-only \
        "${DEPTH_DATA[@]}"
      ;;
    symmetry | viewer-pose)
      calibrate "$pipeline" "crates/pomona-symmetry/models/$pipeline.json" "$pipeline" "${DATA[@]}"
      ;;
    *) echo "calibrate_builtin.sh: no built-in model for pipeline '$pipeline'" >&2; exit 2 ;;
  esac
done
