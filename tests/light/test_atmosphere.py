"""The sky model (light/atmosphere.py) and the day table made from it (light/daytime.py)."""
from __future__ import annotations

import numpy as np
import pytest

from voxel_addon.light import atmosphere as A
from voxel_addon.light import daytime


def _warmth(rgb) -> float:
    return float(rgb[0] / rgb[2])


def test_sky_follows_the_sun():
    noon, dusk = (np.array(daytime.sun_direction(h)) for h in (12.0, 17.9))
    zen = [A.radiance([[0, 0, 1]], s)[0] for s in (noon, dusk)]
    towards = [A.radiance([[s[0], s[1], 0.03] / np.linalg.norm([s[0], s[1], 0.03])], s)[0]
               for s in (noon, dusk)]
    assert zen[0][2] > zen[0][1] > zen[0][0], "noon's zenith is blue"
    assert _warmth(zen[0]) < _warmth(zen[1]), "bluer at noon than at dusk"
    assert _warmth(towards[1]) > 2 * _warmth(towards[0]), "the horizon under the sun warmer at dusk"
    assert A.luminance(zen[0]) > 5 * A.luminance(zen[1]), "and the sky darker"


def test_light_through_the_air():
    high, low, set_ = (A.transmittance(daytime.sun_direction(h)) for h in (12.0, 6.5, 5.5))
    assert (high > low).all() and _warmth(low) > _warmth(high) > 1.0, "the low sun is dimmer, redder"
    assert (set_ == 0).all(), "no direct light from below the horizon"
    e = A.irradiance(daytime.sun_direction(12.0))
    assert (e > 0).all() and e[2] > e[0], "the sky's light is blue"
    # phases integrate to 1 over the sphere
    c = np.linspace(-1, 1, 200001)
    for p in (A.phase_r(c), A.phase_m(c)):
        integral = (p[1:] + p[:-1]).sum() / 2 * (c[1] - c[0])  # trapezoids
        assert integral * 2 * np.pi == pytest.approx(1.0, rel=1e-3)


def test_keys_are_the_model():
    """KEYS (the literal table the bake's ramps also read) is what table() makes."""
    made = daytime.table()
    assert len(made) == len(daytime.KEYS) <= 31  # Blender's colour ramps hold 32 stops
    for a, b in zip(made, daytime.KEYS):
        fa = np.hstack([np.ravel(x) for x in a])
        fb = np.hstack([np.ravel(x) for x in b])
        assert np.allclose(fa, fb, rtol=2e-3, atol=2e-4), (a[0], fa, fb)


def test_day_reads_at_every_hour():
    """Exposure keeps dusk readable and night darker than day (a white flat ground)."""
    def ground(h):
        d = daytime.at(h)
        return A.luminance(np.array(d.ambient) + np.array(d.direct) * max(d.light_dir[2], 0.0))
    noon, dusk, night = ground(12.0), ground(18.5), ground(23.5)
    assert noon > dusk > night
    assert dusk > 0.08 * noon, "dusk stays readable"
    assert night < 0.15 * noon, "night is night"
