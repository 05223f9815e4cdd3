#!/usr/bin/env bash
# Shape-fit trained on two real ak-apples frames, tested on the third under other light
# (docs/results.md, "Real apples under other light"). Needs python3 with numpy and Pillow.
#
#   scripts/ak_other_light.sh [DATA] [OUT]   (POMONA=path/to/pomona uses that binary)
set -euo pipefail
cd "$(dirname "$0")/.."
DATA=${1:-../shared/data/ak-apples}
OUT=${2:-/tmp/pomona-ak-light}
. scripts/pomona_binary.sh
python3 scripts/ak_other_light.py "$DATA" "$OUT"
frames=$(ls "$DATA/color" | sed 's/\.png$//')
for t in $frames; do
  [ -f "$OUT/model-$t.json" ] || "$POMONA" train --pipeline shape-fit --data "$OUT/train-$t" \
    --out "$OUT/model-$t.json" > /dev/null
done
for light in orig dark bright warm cool gamma; do
  found=0; tagged=0
  for t in $frames; do
    det="$OUT/det-$t-$light"
    rm -rf "$det"
    "$POMONA" detect --pipeline shape-fit --model "$OUT/model-$t.json" --data "$OUT/test-$t-$light" \
      --out "$det" > /dev/null
    "$POMONA" eval --data "$OUT/test-$t-$light" --detections "$det" --kind apple \
      --json "$det.json" > /dev/null
    read -r a b <<< "$(python3 -c "import json,sys; r=json.load(open(sys.argv[1])); print(r['true_positives'], r['fruits'])" "$det.json")"
    found=$((found + a)); tagged=$((tagged + b))
  done
  python3 -c "import sys; f,n=int(sys.argv[2]),int(sys.argv[3]); print(f'{sys.argv[1]}: recall {f}/{n} = {f/n:.3f}')" "$light" "$found" "$tagged"
done
