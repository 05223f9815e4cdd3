#!/usr/bin/env bash
# The two 1920x1080 sampling settings of issue 17, each on and off, on five 40-frame synthetic
# Azure Kinect sets (`pomona synth --camera azure-kinect --domain wide --fruit KIND`: peppers
# seeds 3210, 3240, 3241; apples seeds 3211, 3242) with the built-in models:
#   * symmetry and viewer-pose: `boxes.align_samples_min_focal_px` (boxes share one pixel
#     lattice), on = 730 px, off = null;
#   * shape-fit: `normals.keep_sample_count` (the focal-scaled normal window keeps the Kinect
#     v2's sample count), on = true, off = false.
# The model files' own setting is whichever of the two they hold; both are forced here with
# `--set`. Everything through `pomona synth`, `detect --min-confidence 0` and `eval`.
#
#   scripts/azure_1080p_sampling_eval.sh [OUT]        (default /tmp/pomona-1080p)
#
# POMONA=/path/to/pomona uses that binary instead of building one. About 15 min on two cores.
# Prints one Markdown row per pipeline, set and setting (VOC 11-point / all-point AP, precision
# and recall at the model's operating confidence, true / false positives), then the pooled rows
# (mean AP; precision and recall over the five sets' detections).
set -euo pipefail
cd "$(dirname "$0")/.."
OUT=${1:-/tmp/pomona-1080p}
. scripts/pomona_binary.sh
mkdir -p "$OUT/data" "$OUT/det" "$OUT/reports"
SETS=(pepper-3210 pepper-3240 pepper-3241 apple-3211 apple-3242)
for set in "${SETS[@]}"; do
  kind=${set%-*} seed=${set#*-}
  [ -f "$OUT/data/$set/camera.json" ] || "$POMONA" synth --out "$OUT/data/$set" \
    --camera azure-kinect --domain wide --frames 40 --seed "$seed" --fruit "$kind" --force > /dev/null
done

setting() { # pipeline on|off
  case "$1/$2" in
    shape-fit/on) echo "params.normals.keep_sample_count=true" ;;
    shape-fit/off) echo "params.normals.keep_sample_count=false" ;;
    */on) echo "boxes.align_samples_min_focal_px=730" ;;
    */off) echo "boxes.align_samples_min_focal_px=null" ;;
  esac
}
for pipeline in symmetry viewer-pose shape-fit; do
  for value in off on; do
    for set in "${SETS[@]}"; do
      name="$pipeline-$value-$set"
      [ -d "$OUT/det/$name" ] || "$POMONA" detect --pipeline "$pipeline" --data "$OUT/data/$set" \
        --out "$OUT/det/$name" --min-confidence 0 --set "$(setting "$pipeline" "$value")" > /dev/null
      "$POMONA" eval --data "$OUT/data/$set" --detections "$OUT/det/$name" \
        --json "$OUT/reports/$name.json" > /dev/null
    done
  done
done

python3 - "$OUT/reports" "${SETS[@]}" <<'PY'
import json, sys
folder, sets = sys.argv[1], sys.argv[2:]
print("| pipeline | set | setting | AP VOC11 / all-point | P / R at the operating confidence (TP / FP) |")
print("|---|---|---|---|---|")
pooled = []
for pipeline in ["symmetry", "viewer-pose", "shape-fit"]:
    for value in ["off", "on"]:
        tp = fp = fruit = 0
        ap11, ap = [], []
        for s in sets:
            r = json.load(open(f"{folder}/{pipeline}-{value}-{s}.json"))
            tp, fp, fruit = tp + r["true_positives"], fp + r["false_positives"], fruit + r["fruits"]
            ap11.append(r["ap_voc11"])
            ap.append(r["ap"])
            print(f"| {pipeline} | {s} | {value} | {r['ap_voc11']:.3f} / {r['ap']:.3f} | "
                  f"{r['precision']:.3f} / {r['recall']:.3f} ({r['true_positives']} / {r['false_positives']}) |")
        pooled.append(f"| {pipeline} | pooled, {fruit} fruit | {value} | {sum(ap11) / len(ap11):.3f} / "
                      f"{sum(ap) / len(ap):.3f} | {tp / max(1, tp + fp):.3f} / {tp / fruit:.3f} ({tp} / {fp}) |")
print("\n".join(pooled))
PY
