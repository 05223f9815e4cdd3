#!/bin/sh
# Seed 004 §4.2, issue 14: 3D error and matching against the rig's lever d (hub-to-lens
# distance, `--stereo-pivot-m`) and half-turn β, the figures of docs/results.md, "Error against
# the lever d and β". The same orchard scenes (seed 1, D435-sized camera, noise-free rig and
# depth) are shot by every rig; `pomona stereo` locates the fruit from the two colour views with
# Eq. 18 (paper) and triangulation, three ways each: the seed's circle centres (`--no-refine`),
# the earlier whole-patch refinement (`--refine-fruit-chroma off --refine-min-ncc 0.5`) and the
# default refinement (fruit-coloured pixels); then one table. Matching is the seed's relaxation
# (`--match-better-elsewhere off`) throughout, as when the table was measured.
#
#   scripts/stereo_lever_sweep.sh [OUT]   (POMONA=path/to/pomona, FRAMES=60, SEED=1,
#                                          LEVERS="0.3 0.5 0.8 1.0 1.2", BETAS="2 4 8",
#                                          REUSE=1 keeps datasets already rendered in OUT)
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
        if [ "${REUSE:-0}" != 1 ] || [ ! -f "$OUT/$name/rig.json" ]; then
            "$P" synth --out "$OUT/$name" --frames "$FRAMES" --seed "$SEED" --domain orchard \
                --fruit orange --camera d435 --noise none --stereo --stereo-beta-deg "$beta" \
                --stereo-pivot-m "$d" --force >/dev/null
        fi
        for method in paper triangulate; do
            stereo() { # run name, options...
                run=$1
                shift
                "$P" stereo --data "$OUT/$name" --out "$OUT/det-$name-$method-$run" \
                    --method "$method" --report "$OUT/$name-$method-$run.json" \
                    --match-better-elsewhere off "$@" >/dev/null
            }
            stereo circles --no-refine
            stereo whole-patch --refine-fruit-chroma off --refine-min-ncc 0.5
            stereo refined
        done
    done
done
python3 - "$OUT" $LEVERS -- $BETAS <<'PY'
import json, math, os, sys

out, rest = sys.argv[1], sys.argv[2:]
split = rest.index("--")
levers, betas = rest[:split], rest[split + 1:]
runs = ["circles", "whole-patch", "refined"]
fmt = lambda x, spec: "–" if x is None else format(x, spec)
print("| d (m) | β | baseline mm | pairs | precision | recall | method "
      "| median mm: circles / whole patch / refined "
      "| z ≥ 0.8 m (n): circles / whole patch / refined "
      "| abs disparity px: circles / whole patch / refined |")
print("|---|---|---|---|---|---|---|---|---|---|")
for d in levers:
    for beta in betas:
        for method in ["paper", "triangulate"]:
            r = [json.load(open(os.path.join(out, f"d{d}-b{beta}-{method}-{k}.json"))) for k in runs]
            m = r[0]["matching"]
            recall = m["correct"] / m["both_detected"] if m["both_detected"] else None
            c = [x["centre_error"] for x in r]
            p = [x["pixel_error"] for x in r]
            baseline = 2000 * float(d) * math.sin(math.radians(float(beta)))
            cell = lambda xs, key, spec: " / ".join(fmt(x[key], spec) for x in xs)
            print(f"| {d} | {beta}° | {baseline:.0f} | {m['pairs']} | {fmt(m['precision'], '.3f')} "
                  f"| {fmt(recall, '.3f')} | {method} | {cell(c, 'median_mm', '.1f')} "
                  f"| {cell(c, 'median_far_mm', '.1f')} ({c[0]['n_far']}) "
                  f"| {cell(p, 'disparity_median_abs_px', '.2f')} |")
PY
