#!/usr/bin/env bash
# shape-fit's normal window, the same pixels at every depth against grown for surfaces nearer
# than 1 m (`normals.reference_depth_m=1.0`, `normals.grow_only=true`), on test sets larger
# than the cross-domain matrix's: models trained with `pomona train` on the matrix's wide
# training frames (seeds 2001, 2020-2022; 82 frames), tested on three 40-frame sets of other
# seeds — mixed cameras (3301), the D435 (3321), and fruit 0.4-0.8 m away on a Kinect v2
# (3330) — whole and per depth band of the truth fruit (`pomona eval --depth-range-m`).
# Everything through `pomona synth`, `train`, `detect --min-confidence 0` and `eval`.
#
#   scripts/normal_window_eval.sh [OUT] [SEEDS]        (default /tmp/pomona-window, "1 2")
#
# POMONA=/path/to/pomona uses that binary instead of building one. About 40 min on two cores.
# Prints one Markdown row per model, test set and band holding fruit (VOC 11-point AP, fruit
# counted).
set -euo pipefail
cd "$(dirname "$0")/.."
OUT=${1:-/tmp/pomona-window}
SEEDS=${2:-1 2}
. scripts/pomona_binary.sh
mkdir -p "$OUT/data" "$OUT/models" "$OUT/det"

render() { # name seed frames args...
  local name=$1 seed=$2 frames=$3
  shift 3
  [ -f "$OUT/data/$name/camera.json" ] && return 0
  "$POMONA" synth --out "$OUT/data/$name" --frames "$frames" --seed "$seed" --fruit mixed \
    --green-fraction 0.2 --domain wide "$@" --force > /dev/null
}
render train 2001 40
render train-kinect-v2 2020 14 --camera kinect-v2
render train-d435 2021 14 --camera d435
render train-sr4000 2022 14 --camera sr4000
render test-wide 3301 40
render test-d435 3321 40 --camera d435
render test-near 3330 40 --camera kinect-v2 --distance-m 0.4,0.8

declare -A WINDOW=(
  [fixed]="--set normals.reference_depth_m=null --set normals.grow_only=false"
  [grown]="--set normals.reference_depth_m=1.0 --set normals.grow_only=true"
)
echo "| window | seed | test set | depth band (m) | fruit | AP (VOC 11) |"
echo "|---|---|---|---|---|---|"
for window in fixed grown; do
  for seed in $SEEDS; do
    model="$OUT/models/$window-s$seed.json"
    if [ ! -f "$model" ]; then
      # shellcheck disable=SC2086
      "$POMONA" train --pipeline shape-fit --seed "$seed" ${WINDOW[$window]} --out "$model" \
        --data "$OUT/data/train" --data "$OUT/data/train-kinect-v2" \
        --data "$OUT/data/train-d435" --data "$OUT/data/train-sr4000" > /dev/null 2>&1
    fi
    for test in test-wide test-d435 test-near; do
      det="$OUT/det/$window-s$seed-$test"
      [ -d "$det" ] || "$POMONA" detect --pipeline shape-fit --model "$model" \
        --data "$OUT/data/$test" --out "$det" --min-confidence 0 > /dev/null 2>&1
      for band in all 0,0.6 0.6,0.9 0.9,1.2 1.2,3; do
        range=()
        [ "$band" = all ] || range=(--depth-range-m "$band")
        report="$OUT/det/$window-s$seed-$test-${band/,/-}.json"
        "$POMONA" eval --data "$OUT/data/$test" --detections "$det" "${range[@]}" \
          --json "$report" > /dev/null 2>> "$OUT/eval.log"
        python3 - "$report" "$window" "$seed" "$test" "$band" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
if r["fruits"] == 0:
    sys.exit()
ap = "n/a" if r["ap_voc11"] is None else f"{r['ap_voc11']:.3f}"
print(f"| {sys.argv[2]} | {sys.argv[3]} | {sys.argv[4]} | {sys.argv[5]} | {r['fruits']} | {ap} |")
PY
      done
    done
  done
done
