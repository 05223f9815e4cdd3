#!/usr/bin/env bash
# The built-in models on held-out `wide` test sets (seeds never used for training: the built-in
# models use 1000-1002), through `pomona synth`, `detect --min-confidence 0` and `eval` only.
# AP needs every detection; precision and recall are read at the operating confidence the
# detection files record (the model's own), or at score >= 0 for an uncalibrated model.
#
#   scripts/wide_builtin_eval.sh [OUT] [PIPELINE...]      (default: shape-fit symmetry viewer-pose)
#
# POMONA=/path/to/pomona uses that binary instead of building one. Prints a Markdown table and
# writes OUT/table.md. BATCHES="500 510 520" adds the batches of seeds 511-515 and 521-525 (the
# 24 held-out sets of docs/results.md; a set of batch B other than 500 is named NAME-B), and
# DETECT_ARGS="--set KEY=VALUE ..." is passed to every `pomona detect` (give each setting its
# own OUT).
set -euo pipefail
cd "$(dirname "$0")/.."
OUT=${1:-/tmp/pomona-wide-eval}
shift || true
PIPELINES=("$@")
[ ${#PIPELINES[@]} -gt 0 ] || PIPELINES=(shape-fit symmetry viewer-pose)
. scripts/pomona_binary.sh
mkdir -p "$OUT"

# name seed args... : one test set, 10 frames (scripts/wide_sets.txt).
mapfile -t SETS < <(grep -v '^#' scripts/wide_sets.txt)
BATCHES=${BATCHES:-500}
DETECT_ARGS=${DETECT_ARGS:-}
ROWS=()
for pipeline in "${PIPELINES[@]}"; do
  for batch in $BATCHES; do
    for s in "${SETS[@]}"; do
      read -r name seed args <<< "$s"
      if [ "$batch" != 500 ]; then
        name="$name-$batch"
        seed=$((seed - 500 + batch))
      fi
      data="$OUT/data/$name"
      if [ ! -f "$data/camera.json" ]; then
        # shellcheck disable=SC2086
        "$POMONA" synth --out "$data" --frames 10 --seed "$seed" $args --force > /dev/null
      fi
      det="$OUT/det/$pipeline/$name"
      rm -rf "$det"
      # shellcheck disable=SC2086
      "$POMONA" detect --pipeline "$pipeline" --data "$data" --out "$det" --min-confidence 0 \
        $DETECT_ARGS > /dev/null 2>&1 \
        || { "$POMONA" detect --pipeline "$pipeline" --data "$data" --out "$det" $DETECT_ARGS > /dev/null; }
      "$POMONA" eval --data "$data" --detections "$det" --json "$OUT/$pipeline-$name.json" > /dev/null
      ROWS+=("$(python3 - "$OUT/$pipeline-$name.json" "$pipeline" "$name" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
f = lambda v: "n/a" if v is None else f"{v:.3f}"
op = r.get("min_confidence")
point = f"confidence ≥ {op:.3f}" if op is not None else f"score ≥ {r['threshold']}"
print(f"| {sys.argv[2]} | {sys.argv[3]} | {r['fruits']} | {f(r['ap_voc11'])} | {f(r['ap'])} | "
      f"{f(r['precision'])} | {f(r['recall'])} | {point} |")
PY
      )")
    done
  done
done
{
  echo "| pipeline | test set (10 frames) | fruit | AP (VOC 11) | AP (all) | precision | recall | operating point |"
  echo "|---|---|---|---|---|---|---|---|"
  printf "%s\n" "${ROWS[@]}"
} | tee "$OUT/table.md"
