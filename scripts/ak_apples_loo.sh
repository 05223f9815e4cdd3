#!/usr/bin/env bash
# Leave-one-frame-out on the real Azure Kinect orchard frames (../shared/data/ak-apples) through
# the `pomona` binary only: for each of the three frames, train shape-fit on the other two
# (`pomona train`, default training parameters, no hand-set knobs), detect on it
# (`pomona detect`) and score the annotated apples (`pomona eval --kind apple`). Then the three
# test frames' detections are pooled and scored together.
#
#   scripts/ak_apples_loo.sh [OUT] [-- extra `pomona train` arguments, e.g. --set size_prior=\"fixed\"]
#   (POMONA=path/to/pomona uses that binary instead of building one)
#
# OUT (default /tmp/pomona-ak-loo) receives the dataset folders (symlinks into the shared data,
# outside the repository), models, detections and JSON reports. Truth there is incomplete
# (`"complete": false`), so precision is not measured; recall is reported at the default score
# threshold 0 and at any score (threshold -1e9), with the centre and diameter errors of the
# matched apples at threshold 0.
set -euo pipefail
cd "$(dirname "$0")/.."
ROOT=$(pwd)
DATA=${POMONA_AK_DATA:-$ROOT/../shared/data/ak-apples}
OUT=/tmp/pomona-ak-loo
if [ $# -gt 0 ] && [ "$1" != "--" ]; then OUT=$1; shift; fi
[ $# -gt 0 ] && [ "$1" = "--" ] && shift
EXTRA=("$@")
[ -d "$DATA" ] || { echo "no data at $DATA" >&2; exit 2; }
DATA=$(cd "$DATA" && pwd)
. scripts/pomona_binary.sh
rm -rf "$OUT"
mkdir -p "$OUT"

# dataset DIR FRAME... : a dataset folder of symlinks to the chosen frames.
dataset() {
  local dir=$1
  shift
  mkdir -p "$dir/color" "$dir/depth" "$dir/truth"
  ln -s "$DATA/camera.json" "$dir/camera.json"
  for f in "$@"; do
    ln -s "$DATA/color/$f.png" "$dir/color/$f.png"
    ln -s "$DATA/depth/$f.png" "$dir/depth/$f.png"
    ln -s "$DATA/truth/$f.json" "$dir/truth/$f.json"
  done
}

# figures REPORT.json : recall, centre error median, diameter error mean abs (mm).
figures() {
  python3 - "$1" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
def mm(x):
    return "n/a" if x is None else f"{1000 * x:.1f} mm"
rec = r["recall"]
print(f"recall {rec if rec is None else round(rec, 3)} ({r['true_positives']} of {r['fruits']}), "
      f"centre error median {mm(r['center_error_m']['median'])} (mean {mm(r['center_error_m']['mean'])}), "
      f"diameter error mean abs {mm(r['diameter_error_m']['mean_abs'])}")
PY
}

FRAMES=($(ls "$DATA/truth" | sed 's/\.json$//'))
dataset "$OUT/all" "${FRAMES[@]}"
mkdir -p "$OUT/det-all"
for test in "${FRAMES[@]}"; do
  train=()
  for f in "${FRAMES[@]}"; do [ "$f" = "$test" ] || train+=("$f"); done
  fold=$OUT/fold-$test
  dataset "$fold/train" "${train[@]}"
  dataset "$fold/test" "$test"
  start=$(date +%s.%N)
  "$POMONA" train --pipeline shape-fit --data "$fold/train" --out "$fold/model.json" \
    "${EXTRA[@]}" > "$fold/train.log" 2>&1
  end=$(date +%s.%N)
  "$POMONA" detect --pipeline shape-fit --model "$fold/model.json" --data "$fold/test" \
    --out "$fold/det" > "$fold/detect.log" 2>&1
  cp "$fold/det/$test.json" "$OUT/det-all/"
  "$POMONA" eval --data "$fold/test" --detections "$fold/det" --kind apple \
    --json "$fold/eval.json" > "$fold/eval.md" 2>> "$fold/eval.log"
  "$POMONA" eval --data "$fold/test" --detections "$fold/det" --kind apple --threshold -1e9 \
    --json "$fold/eval-any.json" > /dev/null 2>> "$fold/eval.log"
  printf 'fold %s (train %s, %.0f s): %s; at any score: recall %s\n' "$test" "${train[*]}" \
    "$(echo "$end - $start" | bc)" "$(figures "$fold/eval.json")" \
    "$(python3 -c 'import json,sys; print(round(json.load(open(sys.argv[1]))["recall"], 3))' "$fold/eval-any.json")"
done
"$POMONA" eval --data "$OUT/all" --detections "$OUT/det-all" --kind apple \
  --json "$OUT/eval.json" > "$OUT/eval.md" 2>> "$OUT/eval.log"
"$POMONA" eval --data "$OUT/all" --detections "$OUT/det-all" --kind apple --threshold -1e9 \
  --json "$OUT/eval-any.json" > /dev/null 2>> "$OUT/eval.log"
printf 'pooled: %s; at any score: recall %s\n' "$(figures "$OUT/eval.json")" \
  "$(python3 -c 'import json,sys; print(round(json.load(open(sys.argv[1]))["recall"], 3))' "$OUT/eval-any.json")"
