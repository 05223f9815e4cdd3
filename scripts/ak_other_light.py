#!/usr/bin/env python3
"""Leave-one-out datasets of the real `ak-apples` frames with the held-out frame's colour changed
(exposure, white balance, gamma), to check shape-fit under other light (docs/results.md, "Real
apples under other light"). Depth, truth and the training frames are symbolic links into the
data folder, never copies; only the perturbed colour images are written.

    python3 scripts/ak_other_light.py ../shared/data/ak-apples OUT     (needs numpy and Pillow)

Writes OUT/train-<t> (the other two frames) and OUT/test-<t>-<light> for every frame t.
"""
import os
import sys

import numpy as np
from PIL import Image

LIGHTS = {
    "orig": None,
    "dark": lambda x: x * 0.55,
    "bright": lambda x: x * 1.5,
    "warm": lambda x: x * np.array([1.15, 1.0, 0.8]),
    "cool": lambda x: x * np.array([0.85, 1.0, 1.2]),
    "gamma": lambda x: 255.0 * (x / 255.0) ** 1.6,
}


def link(src, dst):
    if not os.path.lexists(dst):
        os.symlink(os.path.abspath(src), dst)


def dataset(src, path, frames, change=None):
    for sub in ("color", "depth", "truth"):
        os.makedirs(os.path.join(path, sub), exist_ok=True)
    link(os.path.join(src, "camera.json"), os.path.join(path, "camera.json"))
    for t in frames:
        link(os.path.join(src, "depth", t + ".png"), os.path.join(path, "depth", t + ".png"))
        link(os.path.join(src, "truth", t + ".json"), os.path.join(path, "truth", t + ".json"))
        colour = os.path.join(src, "color", t + ".png")
        out = os.path.join(path, "color", t + ".png")
        if change is None:
            link(colour, out)
        else:
            x = np.asarray(Image.open(colour).convert("RGB")).astype(np.float64)
            Image.fromarray(np.clip(change(x), 0, 255).round().astype(np.uint8)).save(out)


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    src, out = sys.argv[1], sys.argv[2]
    frames = sorted(f[:-4] for f in os.listdir(os.path.join(src, "color")) if f.endswith(".png"))
    if len(frames) < 2:
        sys.exit(f"{src}: needs at least two frames in color/")
    for t in frames:
        dataset(src, os.path.join(out, "train-" + t), [f for f in frames if f != t])
        for name, change in LIGHTS.items():
            dataset(src, os.path.join(out, f"test-{t}-{name}"), [t], change)


if __name__ == "__main__":
    main()
