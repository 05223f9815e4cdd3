"""Type stubs of the native module ``pomona._pomona`` (import everything from ``pomona``)."""

from os import PathLike
from pathlib import Path
from typing import Any, Mapping, Optional, Sequence, Union

import numpy as np
import numpy.typing as npt

__version__: str

StrPath = Union[str, PathLike[str]]
Camera = Mapping[str, float]

class PomonaError(Exception):
    """A Pomona error; the message names the file, model, parameter or frame at fault."""

class Detector:
    """A fruit detector of one pipeline, loaded once and called many times."""

    def __init__(
        self,
        pipeline: str = "shape-fit",
        model: Optional[StrPath] = None,
        set: Optional[Mapping[str, Any]] = None,
    ) -> None: ...
    @property
    def pipeline(self) -> str: ...
    @property
    def model_id(self) -> str: ...
    @property
    def operating_confidence(self) -> Optional[float]: ...
    def detect(
        self,
        depth: Union[npt.NDArray[np.uint16], npt.NDArray[np.float32]],
        color: Optional[npt.NDArray[np.uint8]] = None,
        *,
        camera: Camera,
        min_confidence: Optional[float] = None,
    ) -> list[dict[str, Any]]: ...
    def write_detections(
        self,
        data: StrPath,
        out: StrPath,
        frames: Optional[Sequence[str]] = None,
        *,
        min_confidence: Optional[float] = None,
    ) -> list[dict[str, Any]]: ...
    def prepare_folder(
        self,
        data: StrPath,
        out: StrPath,
        frames: Optional[Sequence[str]] = None,
        *,
        min_confidence: Optional[float] = None,
    ) -> list[str]: ...

class Tracker:
    """Seed 004's approach tracker, loaded once: a ``color-contour`` model and parameters."""

    def __init__(
        self,
        model: Optional[StrPath] = None,
        set: Optional[Mapping[str, Any]] = None,
    ) -> None: ...
    @property
    def params(self) -> dict[str, Any]: ...
    @property
    def model_id(self) -> str: ...
    def start(self, x: float, y: float, radius: float) -> Track: ...

class StereoLocator:
    """Seed 004's stereo from the two colour shots of a rotating camera (``pomona stereo``)."""

    def __init__(
        self,
        *,
        camera: Mapping[str, float],
        beta_deg: float,
        pivot_m: float,
        model: Optional[StrPath] = None,
        set: Optional[Mapping[str, Any]] = None,
        method: str = "paper",
        min_confidence: Optional[float] = None,
        reach_m: Optional[tuple[float, float]] = None,
        refine: bool = True,
        leftovers: bool = True,
        fruit_radius_m: Optional[tuple[float, float]] = None,
        size_test: bool = True,
    ) -> None: ...
    def locate(
        self, primary: npt.NDArray[np.uint8], stereo: npt.NDArray[np.uint8]
    ) -> list[dict[str, Any]]: ...

class Track:
    """One fruit being followed; ``update`` it with every colour frame."""

    def update(self, color: npt.NDArray[np.uint8]) -> dict[str, Any]: ...
    @property
    def circle(self) -> tuple[float, float, float]: ...

class Dataset:
    """A dataset folder read frame by frame into numpy arrays."""

    def __init__(self, path: StrPath) -> None: ...
    @property
    def path(self) -> Path: ...
    @property
    def frames(self) -> list[str]: ...
    @property
    def has_color(self) -> bool: ...
    @property
    def camera(self) -> dict[str, float]: ...
    def depth(self, frame: str) -> npt.NDArray[np.float32]: ...
    def color(self, frame: str) -> Optional[npt.NDArray[np.uint8]]: ...
    def truth(self, frame: str) -> Optional[dict[str, Any]]: ...
    def cloud(self, frame: str) -> npt.NDArray[np.float32]: ...
    def __len__(self) -> int: ...

def pipelines() -> list[str]: ...
def synth(
    out: StrPath,
    frames: int,
    seed: int,
    *,
    fruit: str = "pepper",
    camera: str = "kinect-v2",
    domain: str = "wide",
    light: str = "day",
    noise: Optional[str] = None,
) -> Dataset: ...
def evaluate(
    data: StrPath,
    detections: StrPath,
    *,
    tolerance_mm: float = 50.0,
    min_visibility: float = 0.5,
    min_confidence: Optional[float] = None,
    threshold: Optional[float] = None,
    image_2d: bool = False,
    depth_range_m: Optional[tuple[float, float]] = None,
) -> dict[str, Any]: ...
def write_failures(
    out: StrPath,
    pipeline: str,
    frames_tried: int,
    failures: Sequence[Mapping[str, Any]],
) -> Optional[Path]: ...
