#!/usr/bin/env python3
"""How far the seen surface leads each detection's centre (docs/results.md, "Free-space check").

    python3 scripts/free_space_leads.py MIN_CONFIDENCE DETECTIONS=DATASET [DETECTIONS=DATASET ...]

DETECTIONS is a folder written by `pomona detect --min-confidence 0`, DATASET its dataset. Each
detection at or above MIN_CONFIDENCE is matched one-to-one to truth centres within 50 mm (best
score first; fruit less than half visible are ignored, as `pomona eval` does), and its lead
`(z_centre - median depth) / radius` is measured as `pomona_pipeline::FreeSpaceCheck` does it
(median over a disc of half the fruit's image radius around the projected centre; a detection
without a diameter counts as 80 mm across).
Prints quantiles of the leads of matched fruit and of false detections, and how many of each a
threshold would refuse. Needs numpy and Pillow.
"""
import glob
import json
import os
import sys

import numpy as np
from PIL import Image

QUANTILES = [0.02, 0.05, 0.1, 0.25, 0.5, 0.75, 0.9]
THRESHOLDS = [-3.0, -2.0, -1.5, -1.0, -0.5, 0.0]


def leads(det_dir, data, min_conf):
    cam = json.load(open(f"{data}/camera.json"))
    fx, fy, cx, cy = cam["fx"], cam["fy"], cam["cx"], cam["cy"]
    unit = cam.get("depth_unit_m", 0.001)
    for path in sorted(glob.glob(f"{det_dir}/*.json")):
        name = os.path.basename(path)[:-5]
        dets = [d for d in json.load(open(path))["detections"]
                if (d.get("confidence") or 0.0) >= min_conf]
        truth = [t for t in json.load(open(f"{data}/truth/{name}.json"))["fruits"]
                 if t.get("center_m") is not None]
        depth = np.asarray(Image.open(f"{data}/depth/{name}.png")).astype(float) * unit
        rows, cols = np.mgrid[0:depth.shape[0], 0:depth.shape[1]]
        used = set()
        for d in sorted(dets, key=lambda d: -d["score"]):
            c = np.array(d["center_m"])
            r = (d.get("diameter_m") or 0.08) / 2
            near = [(np.linalg.norm(c - np.array(t["center_m"])), i) for i, t in enumerate(truth)]
            near = [(dist, i) for dist, i in near if dist <= 0.05 and i not in used]
            if near:
                i = min(near)[1]
                used.add(i)
                label = "fruit" if truth[i].get("visibility", 1.0) >= 0.5 else None
            else:
                label = "false"
            if label is None:
                continue
            u, v = fx * c[0] / c[2] + cx, fy * c[1] / c[2] + cy
            disc = max(1.0, 0.5 * fx * r / c[2])
            inside = ((cols - round(u)) ** 2 + (rows - round(v)) ** 2 <= disc * disc) & (depth > 0)
            if inside.any():
                yield label, (c[2] - np.median(depth[inside])) / r


def main():
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    min_conf = float(sys.argv[1])
    found = {"fruit": [], "false": []}
    for pair in sys.argv[2:]:
        det_dir, data = pair.split("=", 1)
        for label, lead in leads(det_dir, data, min_conf):
            found[label].append(lead)
    for label, values in found.items():
        q = np.quantile(values, QUANTILES) if values else []
        print(f"{label}: {len(values)} detections, lead quantiles {QUANTILES}: {np.round(q, 2)}")
    for t in THRESHOLDS:
        refused = {k: sum(1 for x in v if x < t) for k, v in found.items()}
        print(f"min_lead_radii {t:+.1f}: refuses {refused['fruit']} fruit, {refused['false']} false")


if __name__ == "__main__":
    main()
