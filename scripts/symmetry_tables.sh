#!/usr/bin/env bash
# Seed 000's Tables 1–2 (mean AP and time per frame, pruning × symmetry) and its noise-free
# control, reproduced on synthetic data with `pomona experiment` (issue 5).
#
#   scripts/symmetry_tables.sh [OUT]      (default OUT: /tmp/pomona-symmetry-tables;
#                                          POMONA=path/to/pomona uses that binary)
#
# Data: 60 synthetic SR4000 frames of peppers, half of them green, `tof` noise (and the same
# scenes without noise for the control), dataset seed 11. Protocol: 4 random image-level splits
# (2/3 train, 1/3 test, split seed 1), 50 mm centre tolerance, VOC 11-point AP. Pruning is a
# detection-time switch (`--set highlight.enabled=false`); the fixed frame (no symmetry) is a
# training-time switch (`--train-set frame="fixed"`). `symmetry` runs with its default
# fixed-frame cascade; the `-paper` runs switch it off (`--set cascade.enabled=false`), which is
# seed 000's detector exactly. The control runs the same scenes without noise and with the
# structured-light model `low`. Every run writes OUT/<name>.md (the summary table and stage
# timings) and OUT/<name>.json (per-split reports) and is skipped when its .md exists (delete it
# to rerun); the last step prints one line per run. About 35 minutes on 2 cores.
set -euo pipefail
cd "$(dirname "$0")/.."
OUT=${1:-/tmp/pomona-symmetry-tables}
mkdir -p "$OUT"
. scripts/pomona_binary.sh

for noise in tof none low; do
  [ -d "$OUT/sr4000-$noise" ] || "$POMONA" synth --out "$OUT/sr4000-$noise" --frames 60 \
    --seed 11 --fruit pepper --camera sr4000 --noise "$noise" --green-fraction 0.5 \
    --domain narrow
done

run() {
  local name=$1 pipeline=$2 data=$3
  shift 3
  if [ -s "$OUT/$name.md" ]; then
    echo "== $name: kept from an earlier run" >&2
    return
  fi
  echo "== $name" >&2
  "$POMONA" experiment --pipeline "$pipeline" --data "$OUT/$data" --splits 4 \
    --train-fraction 0.667 --seed 1 --json "$OUT/$name.json" "$@" > "$OUT/$name.md.part"
  mv "$OUT/$name.md.part" "$OUT/$name.md"
}

run tof-symmetry-pruning symmetry sr4000-tof
run tof-symmetry symmetry sr4000-tof --set highlight.enabled=false
run tof-fixed-pruning symmetry sr4000-tof --train-set 'frame="fixed"'
run tof-fixed symmetry sr4000-tof --train-set 'frame="fixed"' --set highlight.enabled=false
run tof-symmetry-pruning-paper symmetry sr4000-tof --set cascade.enabled=false
run tof-symmetry-paper symmetry sr4000-tof --set cascade.enabled=false --set highlight.enabled=false
run tof-viewer-pose viewer-pose sr4000-tof --set highlight.enabled=false
for noise in none low; do
  run "$noise-symmetry" symmetry "sr4000-$noise" --set highlight.enabled=false
  run "$noise-symmetry-paper" symmetry "sr4000-$noise" --set cascade.enabled=false \
    --set highlight.enabled=false
  run "$noise-fixed" symmetry "sr4000-$noise" --train-set 'frame="fixed"' \
    --set highlight.enabled=false
done

for md in "$OUT"/*.md; do
  ap=$(grep 'AP (VOC 11-point)' "$md" | cut -d'|' -f3)
  all=$(grep 'AP (all points)' "$md" | cut -d'|' -f3)
  t=$(grep 'detect time / frame' "$md" | cut -d'|' -f3)
  printf '%-22s VOC11 %s | all-point %s | %s\n' "$(basename "$md" .md)" "$ap" "$all" "$t"
done
