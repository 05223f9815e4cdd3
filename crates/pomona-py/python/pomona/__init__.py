"""Pomona: fruit detection in 3D for harvesting robots, from Python.

Give a detector a depth image (numpy, uint16 sensor units or float32 metres), optionally an RGB
image and the camera, and get each fruit's centre in the camera frame (metres), its diameter and
a calibrated confidence: exactly what ``pomona detect`` writes, computed by the same Rust code.

>>> import numpy as np, pomona
>>> camera = dict(width=64, height=48, fx=60.0, fy=60.0, cx=31.5, cy=23.5, depth_unit_m=0.001)
>>> depth = np.full((48, 64), 800, dtype=np.uint16)          # a flat wall 0.8 m away
>>> pomona.detect(depth, camera=camera, pipeline="symmetry")
[]

``Detector`` loads a model once for many frames, ``Dataset`` reads dataset folders into arrays,
``synth`` renders synthetic datasets, ``evaluate`` scores detection files, and
``pomona.dask.detect_dataset`` spreads a dataset over a Dask cluster (resuming a killed run with
``resume=True``). ``Detector.prepare_folder`` and ``write_failures`` apply the output-folder
rules of ``pomona detect`` for a runner of your own. ``Tracker`` follows one fruit from frame to
frame while the arm closes in (seed 004's approach tracker, as ``pomona track``):
``Tracker().start(x, y, radius)`` from a detection's ``center_px`` and ``radius_px``, then
``track.update(rgb)`` with every frame. ``StereoLocator`` locates fruit from the two colour
shots of a rotating camera, without depth (seed 004's stereo, as ``pomona stereo``).
"""

from __future__ import annotations

import functools
from typing import Any, Mapping, Optional

from pomona._pomona import (
    Dataset,
    Detector,
    PomonaError,
    StereoLocator,
    Track,
    Tracker,
    __version__,
    evaluate,
    pipelines,
    synth,
    write_failures,
)

__all__ = [
    "Dataset",
    "Detector",
    "PomonaError",
    "StereoLocator",
    "Track",
    "Tracker",
    "__version__",
    "detect",
    "evaluate",
    "pipelines",
    "synth",
    "write_failures",
]


@functools.lru_cache(maxsize=8)
def _detector(pipeline: str, model: Optional[str]) -> Detector:
    """The detector of ``pipeline`` and ``model``, loaded once per process."""
    return Detector(pipeline, model=model)


def detect(
    depth: Any,
    color: Any = None,
    *,
    camera: Mapping[str, float],
    pipeline: str = "shape-fit",
    model: Optional[str] = None,
    min_confidence: Optional[float] = None,
) -> list[dict[str, Any]]:
    """Finds fruit in one RGB-D frame.

    ``depth``: a (H, W) uint16 array in ``camera["depth_unit_m"]`` units (0 = no reading) or a
    float32 array in metres; ``color``: a (H, W, 3) uint8 RGB array or ``None`` (depth-only
    pipelines, or the pipeline's depth-only model); ``camera``: a dict with the keys of
    ``camera.json`` (width, height, fx, fy, cx, cy, depth_unit_m); ``pipeline``: one of
    ``pipelines()``; ``model``: a model file from ``pomona train`` (default: the built-in model);
    ``min_confidence``: ``None`` keeps detections at the model's operating confidence (as
    ``pomona detect``; score ≥ 0 for a model without calibration), ``0.0`` keeps everything.

    Returns a list of dicts with the keys of the detection JSON (``center_m``, ``score``,
    ``confidence``, ``diameter_m``, ...). The detector is loaded once per (pipeline, model) and
    kept; the GIL is released while detecting.

    Raises ``TypeError`` for arrays of another dtype or shape and ``PomonaError`` for anything
    the Rust side rejects (unknown pipeline, unreadable model, sizes that disagree).
    """
    return _detector(pipeline, None if model is None else str(model)).detect(
        depth, color, camera=camera, min_confidence=min_confidence
    )
