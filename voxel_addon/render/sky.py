"""Sky, haze, clouds and daylight values of the frame block for a time of day (thesis
§5.5, eq. 5.1 replaced by a physical sky; eq. 4.1).

The key-frame table and the sky model live in `light.daytime` / `light.atmosphere`
(shared with the light model and the bake); this module tabulates the sky's radiance
for the shader (include/atmosphere.glsl: NE elevations x NA azimuths from the sun's)
and derives the discs, the light on the clouds and the stars' pole.
"""
from __future__ import annotations

import math
from functools import lru_cache

import numpy as np

from ..light import atmosphere, daytime

NE, NA = 9, 9          # include/atmosphere.glsl's SKY_NE, SKY_NA (a test checks them)
SUN_DISC = 120.0       # the drawn disc is ~10x the sun's: its radiance less so
MOON_DISC = 2.5        # the moon's disc, in the night's exposed light
CLOUD_ALTITUDE = 4000.0  # m: where the clouds' light comes through the air (pink at dusk)
WIND = (0.94, 0.34)
EPS = 1e-6             # include/atmosphere.glsl's SKY_EPS: the table holds log(radiance + EPS)    # the clouds drift this way (unit vector, world xy)


def nodes(sun_dir) -> np.ndarray:
    """The table's directions (NE*NA, 3): elevation e with sqrt(sin e) evenly spaced
    (dense near the horizon), azimuth 0..pi from the sun's."""
    u = np.linspace(0.0, 1.0, NE)
    el = np.arcsin(np.clip(u * u, 0.0, 1.0))
    el[0] = math.radians(0.3)  # the horizon row: just above it, where the haze is
    az0 = math.atan2(sun_dir[1], sun_dir[0])
    az = az0 + np.linspace(0.0, math.pi, NA)
    e, a = np.meshgrid(el, az, indexing="ij")
    return np.stack([np.cos(e) * np.cos(a), np.cos(e) * np.sin(a), np.sin(e)], -1).reshape(-1, 3)


def _moon_tint():
    t = np.array(daytime.MOON_TINT)
    return t / atmosphere.luminance(t)


@lru_cache(maxsize=16)  # a frame asks for the same hour as the last one
def params(hours: float, exposure_ev: float = 0.0) -> dict:
    """Frame values (shared: do not modify) for the sky, haze and deferred light at
    `hours`, with the hour's exposure (light.daytime) times 2**exposure_ev."""
    d = daytime.at(hours)
    k = 2.0 ** exposure_ev
    ex = d.exposure * k
    sun, moon = np.array(d.sun_dir), np.array(d.moon_dir)
    is_day = d.sun_dir[2] >= 0.0
    rest, mie = daytime.sky_parts(hours, nodes(sun))
    pad = np.zeros((NE * NA, 1))
    t_sun = atmosphere.transmittance(sun)
    tint = _moon_tint()
    disc = t_sun * SUN_DISC * ex if is_day else np.array(daytime.MOON_TINT) * MOON_DISC * k
    # the clouds: lit through the air above the ground (still by the set sun at dusk)
    high = np.array([[0.0, 0.0, atmosphere.R_GROUND + CLOUD_ALTITUDE]])
    t_high = atmosphere._sun_transmittance(high, sun)[0]
    t_moon = atmosphere._sun_transmittance(high, moon)[0] * atmosphere.MOON * tint
    cloud_sun = (t_high + t_moon) / math.pi * ex * 1.3
    t = math.radians(daytime.TILT)
    return {
        "hours": d.hours, "exposure": ex,
        "sun_dir": sun, "moon_dir": moon, "light_dir": np.array(d.light_dir),
        "is_day": is_day,
        "zenith": np.array(d.zenith) * k, "horizon": np.array(d.horizon) * k,
        "halo": np.zeros(3), "disc": disc,
        "ambient": np.array(d.ambient) * k, "direct": np.array(d.direct) * k, "u": float(d.u),
        "stars": float(d.stars),
        "sky_a": np.hstack([np.log(rest * ex + EPS), pad]),
        "sky_b": np.hstack([np.log(mie * ex + EPS), pad]),
        "cloud_sun": cloud_sun, "cloud_sky": np.array(d.ambient) * k * 1.1,
        "pole": np.array([0.0, math.cos(t), math.sin(t)]),
    }


def drift(hours: float, speed: float) -> tuple[float, float]:
    """How far the clouds have moved at `hours` (blocks), `speed` blocks per minute."""
    m = (float(hours) % 24.0) * 60.0 * speed
    return (-WIND[0] * m, -WIND[1] * m)


def godray_scale(p: dict) -> float:
    """What the disc's colour is multiplied by for the god rays (composite.frag): rays as
    bright as the thesis's (half the scene's white by day, less by the moon), whatever
    the disc's radiance and the hour's exposure."""
    lum = float(atmosphere.luminance(p["disc"]))
    return (0.35 if p["is_day"] else 0.08) / max(lum, 1e-6)
