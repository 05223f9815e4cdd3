"""``pomona.StereoLocator``: fruit in 3D from two colour shots (the facade `pomona stereo` runs)."""

from __future__ import annotations

import math

import numpy as np
import pytest

import pomona

CAMERA = dict(width=320, height=240, fx=300.0, fy=300.0, cx=159.5, cy=119.5, depth_unit_m=0.001)
BETA_DEG, PIVOT_M, RADIUS_M = 6.0, 0.3, 0.04
FRUIT = [(-0.15, -0.05, 0.9), (0.05, 0.06, 1.0), (0.2, -0.08, 1.1)]


def in_stereo(p):
    """``p`` (primary camera frame) in the stereo camera's frame: turned by −2β about the
    vertical axis through the hub, ``PIVOT_M`` behind the lens."""
    a = math.radians(-2 * BETA_DEG)
    x, y, z = p[0], p[1], p[2] + PIVOT_M
    return (math.cos(a) * x + math.sin(a) * z, y, -math.sin(a) * x + math.cos(a) * z - PIVOT_M)


def shot(centres, shaded=False) -> np.ndarray:
    """Each sphere as an orange disc of radius f·R/z on leaf green; ``shaded``: darker towards
    its rim (lit from the camera), so that there is something for the refinement to match."""
    h, w = CAMERA["height"], CAMERA["width"]
    y, x = np.mgrid[0:h, 0:w]
    image = np.empty((h, w, 3), dtype=np.uint8)
    image[:] = (40, 80, 30)
    for cx, cy, cz in centres:
        u = CAMERA["fx"] * cx / cz + CAMERA["cx"]
        v = CAMERA["fy"] * cy / cz + CAMERA["cy"]
        rho = np.hypot(x - u, y - v) / (CAMERA["fx"] * RADIUS_M / cz)
        disc = rho <= 1.0
        light = np.sqrt(np.clip(1.0 - rho**2, 0.0, 1.0)) if shaded else np.ones_like(rho)
        for c, value in enumerate((235, 120, 15)):
            image[..., c][disc] = (value * (0.4 + 0.6 * light[disc])).astype(np.uint8)
    return image


@pytest.mark.parametrize("method", ["paper", "triangulate"])
def test_two_shots_locate_each_fruit(method):
    locator = pomona.StereoLocator(
        camera=CAMERA, beta_deg=BETA_DEG, pivot_m=PIVOT_M, method=method, min_confidence=0.0
    )
    found = locator.locate(shot(FRUIT), shot([in_stereo(p) for p in FRUIT]))
    assert len(found) == len(FRUIT), found
    for truth in FRUIT:
        nearest = min(math.dist(d["center_m"], truth) for d in found)
        assert nearest < 0.03, (truth, found)
    for d in found:
        assert d["diameter_m"] == pytest.approx(2 * RADIUS_M, abs=0.02)
    assert "StereoLocator(beta_deg=6.000" in repr(locator)


def test_the_seeds_matching_without_refinement_or_leftover_pass():
    kwargs = dict(camera=CAMERA, beta_deg=BETA_DEG, pivot_m=PIVOT_M, method="triangulate")
    primary, stereo = shot(FRUIT, True), shot([in_stereo(p) for p in FRUIT], True)
    refined = pomona.StereoLocator(min_confidence=0.0, **kwargs).locate(primary, stereo)
    seed = pomona.StereoLocator(
        min_confidence=0.0, refine=False, leftovers=False, **kwargs
    ).locate(primary, stereo)
    assert len(seed) == len(FRUIT), seed
    for truth in FRUIT:
        assert min(math.dist(d["center_m"], truth) for d in seed) < 0.05, (truth, seed)
    # Same circles, other depths: the refinement moves the stereo-view centres.
    assert sorted(d["center_px"] for d in seed) == sorted(d["center_px"] for d in refined)
    assert sorted(d["center_m"] for d in seed) != sorted(d["center_m"] for d in refined)


def test_the_size_test_drops_fruit_located_at_another_size():
    kwargs = dict(camera=CAMERA, beta_deg=BETA_DEG, pivot_m=PIVOT_M, min_confidence=0.0)
    primary, stereo = shot(FRUIT, True), shot([in_stereo(p) for p in FRUIT], True)
    # The fruit are 40 mm in radius: kept by the default range and by 35–45 mm ...
    for extra in ({}, dict(fruit_radius_m=(0.035, 0.045)), dict(size_test=False)):
        found = pomona.StereoLocator(**kwargs, **extra).locate(primary, stereo)
        assert len(found) == len(FRUIT), (extra, found)
    # ... and dropped by a range for smaller fruit, unless the test is off.
    assert pomona.StereoLocator(**kwargs, fruit_radius_m=(0.01, 0.03)).locate(primary, stereo) == []
    off = pomona.StereoLocator(**kwargs, fruit_radius_m=(0.01, 0.03), size_test=False)
    assert len(off.locate(primary, stereo)) == len(FRUIT)
    with pytest.raises(pomona.PomonaError, match="fruit_radius_m"):
        pomona.StereoLocator(**kwargs, fruit_radius_m=(0.05, 0.03))


def test_bad_input_is_refused_by_name():
    with pytest.raises(pomona.PomonaError, match="method"):
        pomona.StereoLocator(camera=CAMERA, beta_deg=BETA_DEG, pivot_m=PIVOT_M, method="x")
    with pytest.raises(pomona.PomonaError, match="rig"):
        pomona.StereoLocator(camera=CAMERA, beta_deg=60.0, pivot_m=PIVOT_M)
    locator = pomona.StereoLocator(camera=CAMERA, beta_deg=BETA_DEG, pivot_m=PIVOT_M)
    small = np.zeros((48, 64, 3), dtype=np.uint8)
    with pytest.raises(pomona.PomonaError):
        locator.locate(small, small)
    with pytest.raises(TypeError):
        locator.locate(np.zeros((240, 320), dtype=np.uint8), shot(FRUIT))
