"""1 vs 2 Dask workers on one dataset (docs/results.md).

    python crates/pomona-py/benches/dask_scaling.py DATASET OUT [PIPELINE] [ROUNDS]

Runs ``pomona.dask.detect_dataset`` on a ``LocalCluster`` of one worker process and of two (one
thread each, ``RAYON_NUM_THREADS=1`` so each worker uses one core), alternately for ROUNDS rounds,
into OUT/1-worker and OUT/2-workers, checks both folders hold the same bytes, and prints the
median wall time and frames per second of each and the speed-up.
"""

from __future__ import annotations

import os
import statistics
import sys
from pathlib import Path

os.environ["RAYON_NUM_THREADS"] = "1"  # inherited by the worker processes

from dask.distributed import Client, LocalCluster  # noqa: E402

from pomona.dask import detect_dataset  # noqa: E402


def files(folder: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted(folder.iterdir())}


def main() -> None:
    data, out = sys.argv[1], Path(sys.argv[2])
    pipeline = sys.argv[3] if len(sys.argv) > 3 else "shape-fit"
    rounds = int(sys.argv[4]) if len(sys.argv) > 4 else 3
    seconds: dict[int, list[float]] = {1: [], 2: []}
    frames = 0
    clusters = {
        n: LocalCluster(n_workers=n, threads_per_worker=1, processes=True, dashboard_address=None)
        for n in (1, 2)
    }
    try:
        clients = {n: Client(c) for n, c in clusters.items()}
        for n, client in clients.items():  # warm-up: workers import pomona and load the model
            detect_dataset(data, out / f"warm-{n}", pipeline=pipeline, client=client)
        for _ in range(rounds):
            for n, client in clients.items():
                summary = detect_dataset(
                    data, out / f"{n}-worker{'s' if n > 1 else ''}", pipeline=pipeline, client=client
                )
                assert summary["failed"] == 0, summary["failures"]
                frames = summary["frames"]
                seconds[n].append(summary["seconds"])
        for client in clients.values():
            client.close()
    finally:
        for cluster in clusters.values():
            cluster.close()
    assert files(out / "1-worker") == files(out / "2-workers"), "outputs differ"
    med = {n: statistics.median(s) for n, s in seconds.items()}
    for n in (1, 2):
        print(f"{n} worker(s): median {med[n]:.2f} s for {frames} frames = {frames / med[n]:.1f} frames/s "
              f"(runs: {', '.join(f'{s:.2f}' for s in seconds[n])})")
    print(f"speed-up 2 vs 1 workers: {med[1] / med[2]:.2f}x ({pipeline}, {data})")


if __name__ == "__main__":
    main()
