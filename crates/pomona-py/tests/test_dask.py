"""``pomona.dask.detect_dataset`` on a ``LocalCluster`` of two worker processes: the same bytes
as ``pomona detect``, failures isolated and listed, and a summary."""

from __future__ import annotations

import json
import subprocess
from pathlib import Path

import pytest

pytest.importorskip("dask.distributed", reason="needs the dask extra: pip install './crates/pomona-py[dask]'")
from dask.distributed import Client, LocalCluster  # noqa: E402

import pomona  # noqa: E402
from pomona.dask import detect_dataset  # noqa: E402


def files(folder: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted(folder.iterdir())}


@pytest.fixture(scope="module")
def client():
    with LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
    ) as cluster, Client(cluster) as client:
        yield client


def test_two_workers_write_exactly_what_pomona_detect_writes(client, oranges, pomona_bin, tmp_path):
    cli = tmp_path / "cli"
    run = subprocess.run(
        [pomona_bin, "detect", "--pipeline", "shape-fit", "--data", oranges.path, "--out", cli],
        capture_output=True, text=True,
    )
    assert run.returncode == 0, run.stderr
    out = tmp_path / "dask"
    summary = detect_dataset(oranges.path, out, pipeline="shape-fit", client=client, batch_size=1)
    assert files(out) == files(cli)
    assert summary["frames"] == 4 and summary["failed"] == 0 and summary["failures"] == []
    assert summary["workers"] == 2 and summary["frames_per_second"] > 0
    assert summary["detections"] == sum(
        len(json.loads(b)["detections"]) for b in files(cli).values()
    )
    # Both worker processes did some of the work.
    pids = client.run(lambda: __import__("os").getpid())
    assert len(set(pids.values())) == 2


def test_a_failing_frame_is_listed_and_the_others_are_written(client, tmp_path):
    data = pomona.synth(tmp_path / "data", 3, 11, fruit="orange", camera="sr4000", domain="narrow")
    bad = data.frames[1]
    (data.path / "depth" / f"{bad}.png").write_bytes(b"not a png")
    out = tmp_path / "det"
    summary = detect_dataset(data.path, out, pipeline="symmetry", client=client)
    assert summary["frames"] == 2 and summary["failed"] == 1
    assert summary["failures"][0]["frame"] == bad
    assert summary["failures"][0]["file"].endswith(f"{bad}.png")
    listed = json.loads((out / "failures.json").read_text())
    assert listed["pipeline"] == "symmetry" and listed["frames_tried"] == 3
    assert [f["frame"] for f in listed["failures"]] == [bad]
    assert sorted(p.name for p in out.glob("0*.json")) == [
        f"{f}.json" for f in data.frames if f != bad
    ]
    # The same folder is still read by pomona.evaluate (failures.json is not a frame).
    assert pomona.evaluate(data.path, out)["frames"] == 3


def test_bad_arguments_fail_on_the_client_before_any_task(client, oranges, tmp_path):
    with pytest.raises(pomona.PomonaError, match="known pipelines"):
        detect_dataset(oranges.path, tmp_path / "x", pipeline="apple-finder", client=client)
    with pytest.raises(pomona.PomonaError):
        detect_dataset(tmp_path / "nowhere", tmp_path / "y", client=client)
