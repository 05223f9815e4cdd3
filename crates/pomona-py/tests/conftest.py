"""Shared fixtures: small synthetic datasets rendered by ``pomona.synth`` (SR4000 camera, 176x144,
so a frame takes milliseconds), and the ``pomona`` binary when one is built."""

from __future__ import annotations

import os
import shutil
from pathlib import Path

import pytest

import pomona

REPO = Path(__file__).resolve().parents[3]


@pytest.fixture(scope="session")
def oranges(tmp_path_factory: pytest.TempPathFactory) -> pomona.Dataset:
    """Four frames of oranges with exact depth, colour and truth."""
    root = tmp_path_factory.mktemp("data") / "oranges"
    return pomona.synth(root, 4, 5, fruit="orange", camera="sr4000", domain="narrow")


@pytest.fixture(scope="session")
def kinect(tmp_path_factory: pytest.TempPathFactory) -> pomona.Dataset:
    """One Kinect v2 frame (512x424) of the wide domain."""
    root = tmp_path_factory.mktemp("data") / "kinect"
    return pomona.synth(root, 1, 7)


@pytest.fixture(scope="session")
def pomona_bin() -> Path:
    """The ``pomona`` binary: ``$POMONA_BIN``, else the workspace's release or debug build (in
    ``$CARGO_TARGET_DIR`` when set). ``scripts/test.sh`` builds it first and sets ``POMONA_BIN``,
    so in CI this never skips."""
    given = os.environ.get("POMONA_BIN")
    target = Path(os.environ.get("CARGO_TARGET_DIR") or REPO / "target")
    if not target.is_absolute():
        target = REPO / target
    candidates = [Path(given)] if given else [
        target / "release" / "pomona",
        target / "debug" / "pomona",
    ]
    for path in candidates:
        if path.is_file():
            return path
    found = shutil.which("pomona")
    if found:
        return Path(found)
    pytest.skip("no pomona binary (build it with `cargo build -p pomona-cli` or set POMONA_BIN)")
