#!/bin/sh
# Seed 004 §4.1–4.2 through the `pomona` binary: the figures of docs/results.md, "### Stereo".
# Orchard oranges seen by a D435-sized camera, exact depth (unused: `pomona stereo` reads only
# the two colour views), the same scenes (seed 1) shot by rigs at β = 2, 4 and 8° (pivot 0.3 m),
# located by Eq. 18 and by triangulation from the circle centres (`--no-refine`, the seed's
# method) after the seed's relaxation (`--match-better-elsewhere off`); then β = 4° through a
# distorted lens.
#
#   scripts/stereo_tables.sh [OUT]      (POMONA=path/to/pomona, FRAMES=20 by default)
set -eu
P=${POMONA:-target/release/pomona}
OUT=${1:-/tmp/pomona-stereo}
FRAMES=${FRAMES:-20}
mkdir -p "$OUT"
run() { # dataset name, synth options...
    name=$1
    shift
    "$P" synth --out "$OUT/$name" --frames "$FRAMES" --seed 1 --domain orchard --fruit orange \
        --camera d435 --noise none --stereo --force "$@"
    for method in paper triangulate; do
        "$P" stereo --data "$OUT/$name" --out "$OUT/det-$name-$method" --method "$method" --no-refine --match-better-elsewhere off \
            --report "$OUT/$name-$method.json"
    done
}
for beta in 2 4 8; do
    run "b$beta" --stereo-beta-deg "$beta"
done
run b4-lens --stereo-beta-deg 4 --distortion -0.2,0.05
"$P" eval --data "$OUT/b4" --detections "$OUT/det-b4-triangulate"
