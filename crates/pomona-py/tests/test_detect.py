"""``pomona.detect`` and ``pomona.Detector``: numpy in, the detection JSON of ``pomona detect``
out, for uint16 and float32 depth, with the GIL released."""

from __future__ import annotations

import json
import subprocess
import threading
import time
from pathlib import Path

import numpy as np
import pytest

import pomona

REPO = Path(__file__).resolve().parents[3]


def raw_depth(dataset: pomona.Dataset, frame: str) -> np.ndarray:
    """The frame's depth as the sensor's uint16 values (as in the PNG)."""
    unit = dataset.camera["depth_unit_m"]
    metres = dataset.depth(frame)
    return np.where(np.isfinite(metres), np.rint(metres / unit), 0).astype(np.uint16)


def files(folder: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted(folder.iterdir())}


def test_detections_equal_the_files_pomona_detect_writes(oranges, pomona_bin, tmp_path):
    for pipeline in pomona.pipelines():
        out = tmp_path / pipeline
        run = subprocess.run(
            [pomona_bin, "detect", "--pipeline", pipeline, "--data", oranges.path,
             "--out", out, "--threads", "1"],
            capture_output=True, text=True,
        )
        assert run.returncode == 0, run.stderr
        detector = pomona.Detector(pipeline)
        found = 0
        for frame in oranges.frames:
            written = json.loads((out / f"{frame}.json").read_text())
            got = detector.detect(
                oranges.depth(frame), oranges.color(frame), camera=oranges.camera
            )
            assert got == written["detections"], (pipeline, frame)
            assert written["model_id"] == detector.model_id
            found += len(got)
        if pipeline == "shape-fit":
            assert found > 0, "the test frames hold oranges shape-fit finds"

        # write_detections (the Dask workers' call) writes the very same bytes.
        again = tmp_path / f"{pipeline}-again"
        rows = detector.write_detections(oranges.path, again)
        assert [r["error"] for r in rows] == [None] * len(oranges)
        assert files(again) == files(out)


def test_uint16_and_float32_depth_give_the_same_detections(oranges):
    frame = oranges.frames[0]
    camera, color = oranges.camera, oranges.color(frame)
    from_raw = pomona.detect(raw_depth(oranges, frame), color, camera=camera, min_confidence=0.0)
    from_metres = pomona.detect(oranges.depth(frame), color, camera=camera, min_confidence=0.0)
    assert from_raw == from_metres
    assert from_raw, "min_confidence=0 keeps every candidate"
    # A non-contiguous view is read correctly too.
    wide = np.zeros((raw_depth(oranges, frame).shape[0], 2 * camera["width"]), np.uint16)
    wide[:, ::2] = raw_depth(oranges, frame)
    assert pomona.detect(wide[:, ::2], color, camera=camera, min_confidence=0.0) == from_raw


def test_thresholds_keep_what_pomona_detect_keeps(oranges):
    detector = pomona.Detector("shape-fit")
    frame = oranges.frames[1]
    args = (oranges.depth(frame), oranges.color(frame))
    everything = detector.detect(*args, camera=oranges.camera, min_confidence=0.0)
    default = detector.detect(*args, camera=oranges.camera)
    op = detector.operating_confidence
    assert op is not None
    assert default == [d for d in everything if d["confidence"] >= op]
    assert len(everything) > len(default) or all(d["confidence"] >= op for d in everything)
    for d in everything:
        assert {"center_m", "score", "confidence"} <= d.keys()
        assert len(d["center_m"]) == 3 and d["center_m"][2] > 0
    with pytest.raises(pomona.PomonaError, match=r"\[0, 1\]"):
        detector.detect(*args, camera=oranges.camera, min_confidence=1.5)


def test_a_model_without_calibration_keeps_what_its_classifier_accepts(oranges, tmp_path):
    # The built-in colour model with its calibration removed: what `pomona train` writes when
    # the truth is incomplete (real frames).
    model = json.loads((REPO / "crates/pomona-shapefit/models/default.json").read_text())
    del model["calibration"]
    path = tmp_path / "uncalibrated.json"
    path.write_text(json.dumps(model))
    detector = pomona.Detector("shape-fit", model=str(path))
    assert detector.operating_confidence is None
    frame = oranges.frames[1]
    args = (oranges.depth(frame), oranges.color(frame))
    everything = detector.detect(*args, camera=oranges.camera, min_confidence=0.0)
    default = detector.detect(*args, camera=oranges.camera)
    assert default == [d for d in everything if d["score"] >= 0.0]
    assert any(d["score"] < 0.0 for d in everything), "some candidates are rejected"
    with pytest.raises(pomona.PomonaError, match="no confidence calibration"):
        detector.detect(*args, camera=oranges.camera, min_confidence=0.5)


def test_bad_input_is_refused_with_a_message_naming_it(oranges):
    frame = oranges.frames[0]
    depth, camera = oranges.depth(frame), oranges.camera
    with pytest.raises(TypeError, match="float64"):
        pomona.detect(depth.astype(np.float64), camera=camera, pipeline="symmetry")
    with pytest.raises(TypeError, match=r"\(H, W, 3\) uint8"):
        pomona.detect(depth, np.zeros(depth.shape, np.uint8), camera=camera)
    with pytest.raises(pomona.PomonaError, match="depth image vs camera"):
        pomona.detect(depth[:-1], camera=camera, pipeline="symmetry")
    with pytest.raises(pomona.PomonaError, match="camera"):
        pomona.detect(depth, camera={"width": 1}, pipeline="symmetry")
    with pytest.raises(pomona.PomonaError, match="known pipelines"):
        pomona.Detector("apple-finder")
    with pytest.raises(pomona.PomonaError, match="no parameter"):
        pomona.Detector("shape-fit", set={"no.such.key": 1})


def test_a_flat_wall_holds_no_fruit():
    camera = dict(width=64, height=48, fx=60.0, fy=60.0, cx=31.5, cy=23.5, depth_unit_m=0.001)
    depth = np.full((48, 64), 800, dtype=np.uint16)
    assert pomona.detect(depth, camera=camera, pipeline="symmetry") == []


def test_the_gil_is_released_while_detecting(kinect):
    """Another Python thread runs while one detection call is in progress."""
    detector = pomona.Detector("shape-fit")
    frame = kinect.frames[0]
    depth, color, camera = kinect.depth(frame), kinect.color(frame), kinect.camera
    detector.detect(depth, color, camera=camera)  # warm caches
    elapsed = []

    def detect_once():
        started = time.perf_counter()
        detector.detect(depth, color, camera=camera)
        elapsed.append(time.perf_counter() - started)

    ticks = 0
    worker = threading.Thread(target=detect_once)
    worker.start()
    while worker.is_alive():
        ticks += 1
        time.sleep(0.0005)
    worker.join()
    # Held for the whole call, the GIL would let this loop run at most once or twice.
    expected = 0.1 * elapsed[0] / 0.0005
    assert ticks >= max(5.0, expected), (ticks, elapsed)
