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

Needs the ``dask`` extra: ``pip install "./crates/pomona-py[dask]"``.
"""

from __future__ import annotations

import json
import math
import os
import tempfile
import time
from pathlib import Path
from typing import Any, Mapping, Optional, Sequence, Union

from pomona._pomona import Dataset, Detector

__all__ = ["detect_dataset"]

FAILURES_FILE = "failures.json"

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


def _write_failures(out: Path, pipeline: str, tried: int, failures: list[dict]) -> Optional[Path]:
    """Writes ``failures.json`` as ``pomona detect`` does (atomically), or removes an old one."""
    path = out / FAILURES_FILE
    if not failures:
        if path.is_file():
            path.unlink()
        return None
    listed = [{"frame": f["frame"], "file": f["file"], "error": f["error"]} for f in failures]
    text = json.dumps(
        {"pipeline": pipeline, "frames_tried": tried, "failures": listed},
        indent=2,
        ensure_ascii=False,
    )
    fd, partial = tempfile.mkstemp(prefix=".pomona-", suffix=".partial", dir=out)
    with os.fdopen(fd, "w", encoding="utf-8") as f:
        f.write(text)
    os.replace(partial, path)
    return path


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
) -> dict[str, Any]:
    """Detects fruit in every frame of the dataset folder ``data`` on a Dask cluster and writes
    ``<out>/<frame>.json`` for each: the same bytes as
    ``pomona detect --pipeline PIPELINE [--model MODEL] --data DATA --out OUT``.

    ``client``: a ``dask.distributed.Client`` (default: the current one). ``min_confidence``,
    ``set`` (stage-parameter overrides, as ``--set``) as for ``Detector``. ``batch_size``: frames
    per task (default: about four tasks per worker thread, at most 64 frames each).

    A frame that fails does not stop the run: it is listed in ``<out>/failures.json`` (as by
    ``pomona detect``) and in the summary. Returns a summary dict: ``frames`` (written),
    ``failed``, ``failures`` (dicts with ``frame``, ``file``, ``error``), ``detections``,
    ``seconds`` (wall time), ``frames_per_second``, ``workers`` and ``threads`` (of the cluster).

    Raises ``PomonaError`` for an unreadable dataset or a model the detector cannot load (checked
    here, before any task is sent).
    """
    from dask.distributed import get_client

    client = client if client is not None else get_client()
    data_dir, out_dir = Path(data).resolve(), Path(out).resolve()
    model_path = None if model is None else str(Path(model).resolve())
    overrides = json.dumps(dict(set or {}), sort_keys=True)
    # Fail early, on the client, for a bad dataset, pipeline, model or threshold.
    detector = _worker_detector(pipeline, model_path, overrides)
    frames = Dataset(data_dir).frames
    out_dir.mkdir(parents=True, exist_ok=True)
    detector.write_detections(data_dir, out_dir, [], min_confidence=min_confidence)

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
    _write_failures(out_dir, pipeline, len(rows), failures)
    done = len(rows) - len(failures)
    return {
        "frames": done,
        "failed": len(failures),
        "failures": [{k: r[k] for k in ("frame", "file", "error")} for r in failures],
        "detections": sum(r["detections"] for r in rows),
        "seconds": seconds,
        "frames_per_second": done / seconds if seconds > 0 else math.inf,
        "workers": len(client.nthreads()),
        "threads": threads,
    }
