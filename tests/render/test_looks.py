"""Looks measured from outside (issue 28, item 4): a 480x270 frame of a small area
beside the sea, clouds off, numbers read off the final sRGB image."""
from __future__ import annotations

import math

import numpy as np

from voxel_addon.render import Camera

from .test_render import floor, renderer
from .test_sky import _sun_yaw

SIZE = (480, 270)
FOV = 70.0
SEA = 61  # the floor's top is z = 60


def _row(elevation: float) -> int:
    """The image row (perspective, pitch 0) at this elevation over the horizon."""
    t = math.tan(math.radians(elevation)) / math.tan(math.radians(FOV / 2))
    return int(round(SIZE[1] / 2 * (1 - t)))


def _hsl_saturation(px) -> np.ndarray:
    px = np.asarray(px, float) / 255.0
    hi, lo = px.max(-1), px.min(-1)
    return (hi - lo) / np.maximum(1e-6, 1 - np.abs(hi + lo - 1))


def _luma(px) -> np.ndarray:
    return np.asarray(px, float) @ [0.2126, 0.7152, 0.0722]


def _views(gl):
    r = renderer(gl, floor(), fov=FOV, sea_level=SEA)
    try:
        noon = r.render(Camera(16, 16, 100, _sun_yaw(12.0) + 180, 0), 12.0, SIZE)
        # towards the sunset, high enough that the sea fills the lower half
        dusk = r.render(Camera(16, 16, 100, _sun_yaw(18.5), 0), 18.5, SIZE)
    finally:
        r.release()
    return noon, dusk


def figures(gl) -> dict:
    noon, dusk = _views(gl)
    sat = float(np.median(_hsl_saturation(noon[_row(10)])))
    # the sea 10 degrees down mirrors the sky 10 degrees up
    sea = float(np.median(_luma(dusk[_row(-10)])))
    sky = float(np.median(_luma(dusk[_row(10)])))
    return {"noon_sky_saturation_10": sat, "dusk_sea_over_sky": sea / sky}


def band(gl) -> float:
    """Below the horizon where nothing is drawn (no sea), at dusk, looking 87 degrees
    beside the set sun as the desert reference scene does (its hard-edged red band):
    the steepest change of brightness across 10 px of the row 30 degrees down, over
    the row's mean."""
    r = renderer(gl, floor(), fov=FOV)
    try:
        img = r.render(Camera(16, 16, 100, _sun_yaw(18.5) - 87, -20), 18.5, SIZE)
    finally:
        r.release()
    t = math.tan(math.radians(-30 + 20)) / math.tan(math.radians(FOV / 2))
    row = _luma(img[int(round(SIZE[1] / 2 * (1 - t)))])
    return float(np.abs(row[10:] - row[:-10]).max() / row.mean())


def test_noon_sky_saturated_and_dusk_sea_mirrors_the_sky(gl):
    f = figures(gl)
    assert f["noon_sky_saturation_10"] >= 0.28, f"noon sky washed out 10 degrees up: {f}"
    assert f["dusk_sea_over_sky"] >= 0.30, f"the dusk sea too dark against its sky: {f}"


def test_no_band_of_the_sunset_down_the_haze(gl):
    """The horizon's glow towards the sun belongs to the horizon: the haze looking down
    is not a (hard-edged) vertical band of it."""
    assert band(gl) < 0.05
