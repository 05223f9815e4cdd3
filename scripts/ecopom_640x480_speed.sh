#!/usr/bin/env bash
# Color-contour time per 640×480 frame of real orchard content (issue 13's speed target is
# stated for 640×480): the eight ECOPOM colour frames (1280×720) scaled to 853×480 and cut to
# their middle 640×480 (intrinsics scaled and shifted with them), detected with the built-in
# model and with a model trained by `pomona train` on the eight full-size frames — the model a
# user with this orchard would run, whose colour class holds every apple. One thread, the
# stage table of `--timings`. Needs python3 with Pillow (docs/results.md, "Speed on real
# orchard content").
#
#   scripts/ecopom_640x480_speed.sh [DATA] [OUT]   (POMONA=path/to/pomona uses that binary)
set -euo pipefail
cd "$(dirname "$0")/.."
DATA=${1:-../shared/data/ecopom-apples-2d}
OUT=${2:-/tmp/pomona-ecopom-640}
. scripts/pomona_binary.sh
mkdir -p "$OUT/data/color"
python3 - "$DATA" "$OUT/data" <<'PY'
import json, pathlib, sys
from PIL import Image
src, dst = pathlib.Path(sys.argv[1]), pathlib.Path(sys.argv[2])
cam = json.loads((src / "camera.json").read_text())
scale = 480 / cam["height"]
wide = round(cam["width"] * scale)
x0 = (wide - 640) // 2
cam.update(fx=cam["fx"] * scale, fy=cam["fy"] * scale, cx=cam["cx"] * scale - x0,
           cy=cam["cy"] * scale, width=640, height=480)
(dst / "camera.json").write_text(json.dumps(cam))
for f in sorted((src / "color").glob("*.png")):
    img = Image.open(f).convert("RGB").resize((wide, 480), Image.BILINEAR)
    img.crop((x0, 0, x0 + 640, 480)).save(dst / "color" / f.name)
PY
[ -f "$OUT/model.json" ] || "$POMONA" train --pipeline color-contour --data "$DATA" \
  --out "$OUT/model.json" > /dev/null
for model in built-in trained; do
  args=()
  [ "$model" = trained ] && args=(--model "$OUT/model.json")
  rm -rf "$OUT/det-$model"
  echo "== $model model"
  "$POMONA" detect --pipeline color-contour "${args[@]}" --data "$OUT/data" --out "$OUT/det-$model" \
    --threads 1 --timings 2>&1 | tail -n 8
done
