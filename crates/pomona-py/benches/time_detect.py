"""Python ``Detector.detect`` against the Rust call on the same frame (docs/results.md).

    RAYON_NUM_THREADS=1 python crates/pomona-py/benches/time_detect.py DATASET [PIPELINE] [ROUNDS] [REPEATS]

Alternates rounds of the Rust example ``time_detect`` (target/release/examples/time_detect, run
as a subprocess) and of the Python call on the first frame of DATASET, so both see the same load,
and prints each side's median over all rounds. The Python side passes the depth as uint16
sensor values (as from a driver) and, separately, as float32 metres; the colour as uint8 RGB.
"""

from __future__ import annotations

import statistics
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

import pomona

REPO = Path(__file__).resolve().parents[3]


def main() -> None:
    data = sys.argv[1]
    pipeline = sys.argv[2] if len(sys.argv) > 2 else "shape-fit"
    rounds = int(sys.argv[3]) if len(sys.argv) > 3 else 5
    repeats = int(sys.argv[4]) if len(sys.argv) > 4 else 10
    rust_bin = REPO / "target" / "release" / "examples" / "time_detect"

    dataset = pomona.Dataset(data)
    frame = dataset.frames[0]
    camera = dataset.camera
    metres = dataset.depth(frame)
    raw = np.where(np.isfinite(metres), np.rint(metres / camera["depth_unit_m"]), 0).astype(np.uint16)
    color = dataset.color(frame)
    detector = pomona.Detector(pipeline)
    detector.detect(raw, color, camera=camera)  # warm-up

    rust_ms: list[float] = []
    py_u16_ms: list[float] = []
    py_f32_ms: list[float] = []
    for round_ in range(rounds):
        out = subprocess.run(
            [rust_bin, data, pipeline, str(repeats)], capture_output=True, text=True, check=True
        ).stdout
        rust_ms += [float(t) for t in out.split("(")[-1].rstrip(")\n").split()]
        sides = [(raw, py_u16_ms), (metres, py_f32_ms)]
        for depth, times in sides if round_ % 2 == 0 else sides[::-1]:  # alternate the order
            for _ in range(repeats):
                started = time.perf_counter()
                detector.detect(depth, color, camera=camera)
                times.append(1e3 * (time.perf_counter() - started))

    rust = statistics.median(rust_ms)
    for name, times in (("python uint16", py_u16_ms), ("python float32", py_f32_ms)):
        py = statistics.median(times)
        print(f"{name}: median {py:.2f} ms, rust {rust:.2f} ms: {100 * (py / rust - 1):+.1f} %")
    print(f"({rounds} rounds x {repeats} calls each side, {pipeline}, frame {frame} of {data})")


if __name__ == "__main__":
    main()
