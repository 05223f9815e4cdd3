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


def cli_detect(pomona_bin: Path, pipeline: str, data: Path, out: Path) -> None:
    """``pomona detect --pipeline PIPELINE --data DATA --out OUT``, which must succeed."""
    run = subprocess.run(
        [pomona_bin, "detect", "--pipeline", pipeline, "--data", data, "--out", out],
        capture_output=True, text=True,
    )
    assert run.returncode == 0, run.stderr


@pytest.fixture(scope="module")
def client():
    with LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
    ) as cluster, Client(cluster) as client:
        yield client


def test_two_workers_write_exactly_what_pomona_detect_writes(client, oranges, pomona_bin, tmp_path):
    cli = tmp_path / "cli"
    cli_detect(pomona_bin, "shape-fit", oranges.path, cli)
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


def test_a_killed_run_resumed_writes_the_cli_files_and_skips_the_done_frames(
    client, oranges, pomona_bin, tmp_path
):
    cli = tmp_path / "cli"
    cli_detect(pomona_bin, "shape-fit", oranges.path, cli)
    out = tmp_path / "dask"
    detect_dataset(oranges.path, out, pipeline="shape-fit", client=client, batch_size=1)
    # Killed half-way: two frames never written, one atomic write cut short.
    lost = [oranges.frames[1], oranges.frames[3]]
    for frame in lost:
        (out / f"{frame}.json").unlink()
    (out / ".pomona-x.partial").write_text('{"frame": "half')
    kept = {f: (out / f"{f}.json").stat().st_ino for f in oranges.frames if f not in lost}

    summary = detect_dataset(
        oranges.path, out, pipeline="shape-fit", client=client, batch_size=1, resume=True
    )
    assert summary["skipped"] == 2 and summary["frames"] == 2 and summary["failed"] == 0
    assert files(out) == files(cli), "resumed output differs from one whole CLI run"
    # The done frames were not written again (an atomic write would replace the file).
    assert {f: (out / f"{f}.json").stat().st_ino for f in kept} == kept

    # Resumed with nothing left, nothing is sent; without resume, every file is written again
    # (as `pomona detect` without --resume), to the same bytes.
    summary = detect_dataset(oranges.path, out, pipeline="shape-fit", client=client, resume=True)
    assert summary["skipped"] == 4 and summary["frames"] == 0
    summary = detect_dataset(oranges.path, out, pipeline="shape-fit", client=client)
    assert summary["skipped"] == 0 and summary["frames"] == 4
    assert all((out / f"{f}.json").stat().st_ino != ino for f, ino in kept.items())
    assert files(out) == files(cli)


@pytest.mark.parametrize("resume", [False, True])
def test_a_folder_of_another_run_is_refused_naming_the_file_before_any_task(
    client, oranges, pomona_bin, tmp_path, resume
):
    out = tmp_path / "det"
    cli_detect(pomona_bin, "symmetry", oranges.path, out)
    before = files(out)
    first = f"{oranges.frames[0]}.json"
    with pytest.raises(pomona.PomonaError, match=rf"{first}.*pipeline `symmetry`.*refusing to mix"):
        detect_dataset(oranges.path, out, pipeline="shape-fit", client=client, resume=resume)
    with pytest.raises(pomona.PomonaError, match=rf"{first}.*minimum confidence.*refusing to mix"):
        detect_dataset(
            oranges.path, out, pipeline="symmetry", client=client, resume=resume,
            min_confidence=0.0,
        )
    # No task ran: every file is as the CLI left it.
    assert files(out) == before

    # A <frame>.json that is not a detection file is never overwritten.
    mine = out / f"{oranges.frames[2]}.json"
    mine.write_text('{"notes": "my own file"}')
    with pytest.raises(pomona.PomonaError, match=rf"{mine.name} is not a detection file"):
        detect_dataset(oranges.path, out, pipeline="symmetry", client=client, resume=resume)
    assert mine.read_text() == '{"notes": "my own file"}'


def test_stale_partial_files_are_removed_and_an_old_failures_list_goes(client, oranges, tmp_path):
    out = tmp_path / "det"
    out.mkdir()
    for name in (".pomona-x.partial", ".pomona-7Qa.partial"):
        (out / name).write_text("{")
    (out / "notes.partial").write_text("not ours")
    (out / "failures.json").write_text('{"pipeline": "symmetry", "frames_tried": 4, "failures": []}')
    summary = detect_dataset(oranges.path, out, pipeline="symmetry", client=client)
    assert summary["frames"] == 4 and summary["failed"] == 0
    assert sorted(p.name for p in out.iterdir()) == sorted(
        [f"{f}.json" for f in oranges.frames] + ["notes.partial"]
    )
