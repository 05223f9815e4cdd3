"""Detection over a Dask cluster: ``detect_dataset`` spreads a dataset's frames over the workers
of a ``dask.distributed`` cluster and writes the same files, byte for byte, as ``pomona detect``.

Why Dask: teams that process a season of recordings already run a cluster engine; Dask runs the
same call on a laptop (``LocalCluster``), on Slurm (``dask_jobqueue.SLURMCluster``) or on
Kubernetes (``dask_kubernetes``), so Pomona needs no scheduler of its own. The dataset and the
output folder must be on storage every worker sees (a shared volume).

Frames are sent to the workers in batches (a list of frame names, never the images); each worker
process loads the detector once and keeps it for every later batch, reads its frames from the
dataset folder and writes their detection files itself. Detection runs in Rust with the GIL
released, so a worker with several threads detects on several cores.

The output folder follows the rules of ``pomona detect``, checked on the client by the same Rust
code before any task is sent: a folder holding detection files of another pipeline, model,
parameter override or ``min_confidence``, or a ``<frame>.json`` that is not a detection file, is
refused (``PomonaError`` naming the file); temporaries a killed run left are removed; with
``resume=True`` the frames whose file this run would write are skipped, so a killed run (or a
lost worker) is continued rather than redone. ``failures.json`` is written by the same Rust code
as the CLI's.

Needs the ``dask`` extra: ``pip install "./crates/pomona-py[dask]"``.
"""

from __future__ import annotations

import json
import math
import os
import time
from pathlib import Path
from typing import Any, Mapping, Optional, Sequence, Union

from pomona._pomona import Dataset, Detector, write_failures

__all__ = ["detect_dataset"]

# Detectors loaded in this (worker) process, by what identifies them.
_DETECTORS: dict[tuple[str, Optional[str], str], Detector] = {}


def _worker_detector(
    pipeline: str, model: Optional[str], overrides: str
) -> Detector:
    """The detector of this worker process for ``(pipeline, model, overrides)``, loaded once."""
    key = (pipeline, model, overrides)
    if key not in _DETECTORS:
        _DETECTORS[key] = Detector(pipeline, model=model, set=json.loads(overrides))
    return _DETECTORS[key]


def _detect_batch(
    frames: Sequence[str],
    data: str,
    out: str,
    pipeline: str,
    model: Optional[str],
    overrides: str,
    min_confidence: Optional[float],
) -> list[dict[str, Any]]:
    """Runs on a worker: detects in ``frames`` of ``data`` and writes their files into ``out``."""
    detector = _worker_detector(pipeline, model, overrides)
    return detector.write_detections(
        data, out, list(frames), min_confidence=min_confidence
    )


def _batches(frames: Sequence[str], size: int) -> list[list[str]]:
    return [list(frames[i : i + size]) for i in range(0, len(frames), size)]


def detect_dataset(
    data: Union[str, os.PathLike],
    out: Union[str, os.PathLike],
    pipeline: str = "shape-fit",
    model: Optional[Union[str, os.PathLike]] = None,
    client: Any = None,
    *,
    min_confidence: Optional[float] = None,
    set: Optional[Mapping[str, Any]] = None,
    batch_size: Optional[int] = None,
    resume: bool = False,
) -> dict[str, Any]:
    """Detects fruit in every frame of the dataset folder ``data`` on a Dask cluster and writes
    ``<out>/<frame>.json`` for each: the same bytes as
    ``pomona detect --pipeline PIPELINE [--model MODEL] --data DATA --out OUT``.

    ``client``: a ``dask.distributed.Client`` (default: the current one). ``min_confidence``,
    ``set`` (stage-parameter overrides, as ``--set``) as for ``Detector``. ``batch_size``: frames
    per task (default: about four tasks per worker thread, at most 64 frames each).

    ``out`` may hold files of an earlier run. Detection files made by this same run (pipeline,
    model, ``set`` and ``min_confidence``) are written again, or skipped with ``resume=True`` (as
    ``pomona detect --resume``: continue a killed run); stale ``.pomona-*.partial`` temporaries
    are removed.

    A frame that fails does not stop the run: it is listed in ``<out>/failures.json`` (as by
    ``pomona detect``) and in the summary. Returns a summary dict: ``frames`` (written),
    ``skipped`` (already done, with ``resume=True``), ``failed``, ``failures`` (dicts with
    ``frame``, ``file``, ``error``), ``detections``, ``seconds`` (wall time),
    ``frames_per_second``, ``workers`` and ``threads`` (of the cluster).

    Raises ``PomonaError``, before any task is sent, for an unreadable dataset, a model the
    detector cannot load, a bad threshold, and an output folder holding a ``<frame>.json`` that
    is not a detection file or was made by another pipeline, model or threshold (the message
    names the file and what differs).
    """
    from dask.distributed import get_client

    client = client if client is not None else get_client()
    data_dir, out_dir = Path(data).resolve(), Path(out).resolve()
    model_path = None if model is None else str(Path(model).resolve())
    overrides = json.dumps(dict(set or {}), sort_keys=True)
    # Fail early, on the client, for a bad dataset, pipeline, model, threshold or output folder.
    detector = _worker_detector(pipeline, model_path, overrides)
    everything = Dataset(data_dir).frames
    # (`set` is the overrides argument here, hence frozenset.)
    done = frozenset(detector.prepare_folder(data_dir, out_dir, min_confidence=min_confidence))
    frames = [f for f in everything if not (resume and f in done)]
    skipped = len(everything) - len(frames)

    threads = sum(client.nthreads().values()) or 1
    size = batch_size or max(1, min(64, math.ceil(len(frames) / (4 * threads))))
    started = time.perf_counter()
    futures = client.map(
        _detect_batch,
        _batches(frames, size),
        data=str(data_dir),
        out=str(out_dir),
        pipeline=pipeline,
        model=model_path,
        overrides=overrides,
        min_confidence=min_confidence,
        pure=False,
    )
    rows = [row for batch in client.gather(futures) for row in batch]
    seconds = time.perf_counter() - started
    failures = [r for r in rows if r["error"] is not None]
    write_failures(out_dir, pipeline, len(rows), failures)
    written = len(rows) - len(failures)
    return {
        "frames": written,
        "skipped": skipped,
        "failed": len(failures),
        "failures": [{k: r[k] for k in ("frame", "file", "error")} for r in failures],
        "detections": sum(r["detections"] for r in rows),
        "seconds": seconds,
        "frames_per_second": written / seconds if seconds > 0 else math.inf,
        "workers": len(client.nthreads()),
        "threads": threads,
    }
