"""Frames per second per core for each pipeline (docs/results.md).

    python crates/pomona-py/benches/fps_per_core.py DATASET OUT

Runs ``Detector(pipeline).write_detections(DATASET, OUT/<pipeline>)`` (the Dask workers' call:
read the frame, detect, write its file; the same Rust path as ``pomona detect --threads 1``) on
one core (``RAYON_NUM_THREADS=1``) for every built-in pipeline, and prints the wall-clock frames
per second (reading and writing included), the same from the process's CPU time (what a core of
its own would give on a loaded machine) and the mean detection time per frame.
"""

from __future__ import annotations

import os
import sys
import time
from pathlib import Path

os.environ["RAYON_NUM_THREADS"] = "1"  # before the extension starts its thread pool

import pomona  # noqa: E402


def main() -> None:
    data, out = sys.argv[1], Path(sys.argv[2])
    frames = len(pomona.Dataset(data))
    print(f"| pipeline | frames/s (wall) | frames/s per CPU-second | detection ms/frame (wall) |")
    print("|---|---|---|---|")
    for pipeline in pomona.pipelines():
        detector = pomona.Detector(pipeline)
        started, cpu_started = time.perf_counter(), time.process_time()
        rows = detector.write_detections(data, out / pipeline)
        wall = time.perf_counter() - started
        cpu = time.process_time() - cpu_started
        failed = [r for r in rows if r["error"]]
        assert not failed, failed
        detect_ms = 1e3 * sum(r["seconds"] for r in rows) / len(rows)
        print(f"| {pipeline} | {len(rows) / wall:.1f} | {len(rows) / cpu:.1f} | {detect_ms:.1f} |")
    print(f"({frames} frames of {data}, one thread)")


if __name__ == "__main__":
    main()
