"""Sky and daylight uniforms for a time of day (thesis §5.5, eq. 5.1; eq. 4.1).

The key-frame table lives in `light.daytime` (shared with the light model and the
bake); this module only derives what eq. 5.1 needs beyond it (halo, disc colours).
"""
from __future__ import annotations

from functools import lru_cache

import numpy as np

from ..light import daytime


@lru_cache(maxsize=16)  # a frame asks for the same hour as the last one
def params(hours: float) -> dict:
    """Uniform values (shared: do not modify) for the sky, fog and deferred light at `hours`."""
    d = daytime.at(hours)
    sun, moon = np.array(d.sun_dir), np.array(d.moon_dir)
    is_day = d.sun_dir[2] >= 0.0
    disc = np.array(d.sun_color if is_day else d.moon_color)
    # the halo glows warm when the body is low (eq. 5.1's c_halo), faint by night
    low = 1.0 - min(1.0, abs(d.light_dir[2]) * 2.5)
    halo = disc * (0.15 + 0.45 * low) * (1.0 if is_day else 0.25)
    return {
        "hours": d.hours,
        "sun_dir": sun, "moon_dir": moon, "light_dir": np.array(d.light_dir),
        "is_day": is_day,
        "zenith": np.array(d.zenith), "horizon": np.array(d.horizon),
        "halo": halo, "disc": disc * (4.0 if is_day else 1.2),
        "ambient": np.array(d.ambient), "direct": np.array(d.direct), "u": float(d.u),
        "stars": float(d.stars),
    }
