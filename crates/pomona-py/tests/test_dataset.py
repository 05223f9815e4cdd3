"""``pomona.Dataset``, ``pomona.synth`` and ``pomona.evaluate``: dataset folders as numpy arrays,
synthetic datasets, and the evaluation report of ``pomona eval``."""

from __future__ import annotations

import subprocess

import numpy as np
import pytest

import pomona


def test_a_dataset_reads_frames_as_arrays(oranges):
    assert len(oranges) == 4 and oranges.frames == sorted(oranges.frames)
    camera = oranges.camera
    assert set(camera) == {"width", "height", "fx", "fy", "cx", "cy", "depth_unit_m"}
    assert (camera["width"], camera["height"]) == (176, 144)
    frame = oranges.frames[0]
    depth = oranges.depth(frame)
    assert depth.dtype == np.float32 and depth.shape == (144, 176)
    valid = np.isfinite(depth)
    assert valid.any() and (depth[valid] > 0).all()
    color = oranges.color(frame)
    assert color is not None and color.dtype == np.uint8 and color.shape == (144, 176, 3)
    truth = oranges.truth(frame)
    assert truth is not None and truth["fruits"], "synthetic frames carry exact truth"
    assert all(f["kind"] == "orange" for f in truth["fruits"])


def test_a_cloud_is_the_back_projected_valid_depth(oranges):
    frame = oranges.frames[0]
    depth, camera = oranges.depth(frame), oranges.camera
    cloud = oranges.cloud(frame)
    assert cloud.dtype == np.float32 and cloud.ndim == 2 and cloud.shape[1] == 3
    v, u = np.nonzero(np.isfinite(depth))
    assert cloud.shape[0] == len(u)
    z = depth[v, u]
    expected = np.stack(
        [(u - camera["cx"]) * z / camera["fx"], (v - camera["cy"]) * z / camera["fy"], z], axis=1
    )
    np.testing.assert_allclose(cloud, expected, rtol=1e-5, atol=1e-6)


def test_synth_is_deterministic_and_guards_its_folder(tmp_path):
    a = pomona.synth(tmp_path / "a", 1, 3, camera="sr4000", domain="narrow")
    b = pomona.synth(tmp_path / "b", 1, 3, camera="sr4000", domain="narrow")
    frame = a.frames[0]
    np.testing.assert_array_equal(a.depth(frame), b.depth(frame))
    with pytest.raises(pomona.PomonaError, match="already holds a dataset"):
        pomona.synth(tmp_path / "a", 1, 3)
    with pytest.raises(pomona.PomonaError, match="unknown camera"):
        pomona.synth(tmp_path / "c", 1, 3, camera="kinect-v9")
    with pytest.raises(pomona.PomonaError, match="cannot|not|No such"):
        pomona.Dataset(tmp_path / "nowhere")


def test_orchard_synth_writes_what_pomona_synth_writes(pomona_bin, tmp_path):
    got = pomona.synth(
        tmp_path / "py", 1, 4, fruit="orange", camera="sr4000", domain="orchard", light="dim"
    )
    subprocess.run(
        [pomona_bin, "synth", "--out", tmp_path / "cli", "--frames", "1", "--seed", "4",
         "--fruit", "orange", "--camera", "sr4000", "--domain", "orchard", "--light", "dim"],
        check=True, capture_output=True,
    )
    cli = pomona.Dataset(tmp_path / "cli")
    frame = got.frames[0]
    assert cli.frames == got.frames
    np.testing.assert_array_equal(got.color(frame), cli.color(frame))
    np.testing.assert_array_equal(got.depth(frame), cli.depth(frame))
    assert got.truth(frame) == cli.truth(frame)
    assert got.truth(frame)["synth"]["light"] == "dim"
    with pytest.raises(pomona.PomonaError, match="unknown light preset `night`"):
        pomona.synth(tmp_path / "x", 1, 4, domain="orchard", light="night")
    with pytest.raises(pomona.PomonaError, match="unknown domain"):
        pomona.synth(tmp_path / "y", 1, 4, domain="vineyard")


def test_evaluate_scores_detection_files_against_truth(oranges, tmp_path):
    out = tmp_path / "det"
    detector = pomona.Detector("shape-fit")
    detector.write_detections(oranges.path, out)
    report = pomona.evaluate(oranges.path, out)
    assert report["frames"] == 4 and report["fruits"] > 0
    assert report["min_confidence"] == detector.operating_confidence, "as the files record"
    assert report["ap_voc11"] is not None and 0.0 < report["ap_voc11"] <= 1.0
    strict = pomona.evaluate(oranges.path, out, tolerance_mm=0.001)
    assert strict["true_positives"] < report["true_positives"]
    beyond = pomona.evaluate(oranges.path, out, depth_range_m=(5.0, 6.0))
    assert beyond["fruits"] == 0 and beyond["depth_range_m"] == [5.0, 6.0]
    with pytest.raises(pomona.PomonaError, match="depth_range_m"):
        pomona.evaluate(oranges.path, out, depth_range_m=(1.0, 0.5))
