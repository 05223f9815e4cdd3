"""``pomona.Tracker``: seed 004's approach tracker from numpy frames, equal to ``pomona track``."""

from __future__ import annotations

import json
import subprocess

import numpy as np
import pytest

import pomona


def disc_frame(cx: float, cy: float, r: float, size=(120, 160)) -> np.ndarray:
    """An orange disc on leaf green."""
    h, w = size
    y, x = np.mgrid[0:h, 0:w]
    frame = np.empty((h, w, 3), dtype=np.uint8)
    frame[:] = (40, 110, 35)
    frame[np.hypot(x - cx, y - cy) <= r] = (235, 120, 20)
    return frame


def test_a_moving_disc_is_followed():
    track = pomona.Tracker().start(60.0, 60.0, 15.0)
    for k in range(8):
        cx, r = 60.0 + 4 * k, 15.0 + 0.5 * k
        estimate = track.update(disc_frame(cx, 60.0, r))
        assert estimate["status"] in ("confirmed", "searched", "redetected"), estimate
        x, y = estimate["center_px"]
        assert np.hypot(x - cx, y - 60.0) < 1.5, (k, estimate)
        assert abs(estimate["radius_px"] - r) < 1.5, (k, estimate)
    assert track.circle == pytest.approx((x, y, estimate["radius_px"]))


def test_tracks_equal_pomona_track(oranges, pomona_bin, tmp_path):
    """The CLI's track of a circle through a dataset, frame by frame, from Python."""
    start = (88.0, 72.0, 20.0)
    out = tmp_path / "track"
    run = subprocess.run(
        [pomona_bin, "track", "--data", oranges.path, "--out", out,
         "--start", ",".join(str(v) for v in start)],
        capture_output=True, text=True,
    )
    assert run.returncode == 0, run.stderr
    cli = json.loads((out / "track.json").read_text())["frames"]
    track = pomona.Tracker().start(*start)
    ours = [track.update(oranges.color(frame)) for frame in oranges.frames]
    assert [f["frame"] for f in cli] == oranges.frames
    for a, b in zip(cli, ours):
        assert a["center_px"] == b["center_px"] and a["radius_px"] == b["radius_px"], (a, b)
        assert a["status"] == b["status"] and a["probes"] == b["probes"], (a, b)


def test_parameters_and_bad_input_give_clear_errors():
    tracker = pomona.Tracker(set={"max_radius_change": 1.2, "edge_scan.gap_px": 3})
    assert tracker.params["max_radius_change"] == 1.2
    assert tracker.params["edge_scan"]["gap_px"] == 3
    assert len(tracker.model_id) == 16
    with pytest.raises(pomona.PomonaError, match="max_radius_chnage"):
        pomona.Tracker(set={"max_radius_chnage": 1.2})
    with pytest.raises(pomona.PomonaError, match="no/such/model.json"):
        pomona.Tracker(model="no/such/model.json")
    with pytest.raises(pomona.PomonaError, match="radius"):
        tracker.start(10.0, 10.0, 0.0)
    track = tracker.start(10.0, 10.0, 5.0)
    with pytest.raises(TypeError):
        track.update(np.zeros((48, 64), dtype=np.uint8))
    # A frame without fruit colour: lost, the last circle kept.
    estimate = track.update(np.full((48, 64, 3), 90, dtype=np.uint8))
    assert estimate["status"] == "lost"
    assert track.circle == (10.0, 10.0, 5.0)
