#!/bin/sh
# Seed 004 §4.2, issue 14: 3D error and matching against the rig's lever d (hub-to-lens
# distance, `--stereo-pivot-m`) and half-turn β, the figures of docs/results.md, "Error against
# the lever d and β". The same orchard scenes (seed 1, D435-sized camera, noise-free rig and
# depth) are shot by every rig; `pomona stereo` locates the fruit from the two colour views with
# Eq. 18 (paper) and triangulation, each with and without `--refine`; then one table.
#
#   scripts/stereo_lever_sweep.sh [OUT]   (POMONA=path/to/pomona, FRAMES=60, SEED=1,
#                                          LEVERS="0.3 0.5 0.8 1.0 1.2", BETAS="2 4 8")
set -eu
P=${POMONA:-target/release/pomona}
OUT=${1:-/tmp/pomona-stereo-lever}
FRAMES=${FRAMES:-60}
SEED=${SEED:-1}
LEVERS=${LEVERS:-0.3 0.5 0.8 1.0 1.2}
BETAS=${BETAS:-2 4 8}
mkdir -p "$OUT"
for d in $LEVERS; do
    for beta in $BETAS; do
        name="d${d}-b${beta}"
        "$P" synth --out "$OUT/$name" --frames "$FRAMES" --seed "$SEED" --domain orchard \
            --fruit orange --camera d435 --noise none --stereo --stereo-beta-deg "$beta" \
            --stereo-pivot-m "$d" --force >/dev/null
        for method in paper triangulate; do
            "$P" stereo --data "$OUT/$name" --out "$OUT/det-$name-$method" --method "$method" \
                --report "$OUT/$name-$method.json" >/dev/null
            "$P" stereo --data "$OUT/$name" --out "$OUT/det-$name-$method-refine" \
                --method "$method" --refine --report "$OUT/$name-$method-refine.json" >/dev/null
        done
    done
done
python3 - "$OUT" $LEVERS -- $BETAS <<'PY'
import json, os, sys

out, rest = sys.argv[1], sys.argv[2:]
split = rest.index("--")
levers, betas = rest[:split], rest[split + 1:]
fmt = lambda x, spec: "–" if x is None else format(x, spec)
print("| d (m) | β | baseline mm | pairs | precision | recall | method | median mm, circles / refined "
      "| z ≥ 0.8 m mm (n), circles / refined | abs disparity px, circles / refined |")
print("|---|---|---|---|---|---|---|---|---|---|")
for d in levers:
    for beta in betas:
        for method in ["paper", "triangulate"]:
            runs = [json.load(open(os.path.join(out, f"d{d}-b{beta}-{method}{r}.json")))
                    for r in ["", "-refine"]]
            m = runs[0]["matching"]
            recall = m["correct"] / m["both_detected"] if m["both_detected"] else None
            c = [r["centre_error"] for r in runs]
            p = [r["pixel_error"] for r in runs]
            baseline = 2000 * float(d) * __import__("math").sin(__import__("math").radians(float(beta)))
            print(f"| {d} | {beta}° | {baseline:.0f} | {m['pairs']} | {fmt(m['precision'], '.3f')} "
                  f"| {fmt(recall, '.3f')} | {method} "
                  f"| {fmt(c[0]['median_mm'], '.1f')} / {fmt(c[1]['median_mm'], '.1f')} "
                  f"| {fmt(c[0]['median_far_mm'], '.1f')} / {fmt(c[1]['median_far_mm'], '.1f')} ({c[0]['n_far']}) "
                  f"| {fmt(p[0]['disparity_median_abs_px'], '.2f')} / {fmt(p[1]['disparity_median_abs_px'], '.2f')} |")
PY
