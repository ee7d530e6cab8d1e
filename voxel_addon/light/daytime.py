"""Time of day: the one parameter table shared by the light model (eq. 4.1) and the sky.

Conventions (world axes, z up, SPEC §3):
- `hours` is the time of day in [0, 24): 0 = midnight, 12 = noon; values wrap.
- The sun rises exactly in +x at 06:00, culminates at 12:00 and sets in -x at 18:00.
  Its orbit plane is tilted by TILT degrees towards -y, so at noon it stands at
  90 - TILT degrees elevation slightly to the -y side (shadows are never exactly
  vertical). The moon is always opposite the sun.
- `sun_dir` / `moon_dir` are unit vectors pointing from the scene *towards* the body.
- `light_dir` is the direction eq. 4.1 uses for the directional daylight term
  (the sun while it is above the horizon, else the moon); `direct` is that term's colour.
  `direct` fades to ~0 at sunrise/sunset so the switch between bodies does not pop.
- Colours are linear RGB floats. `u` is the artificial-light reduction of eq. 4.1
  (0 at night, up to 0.8 at noon).

Colours are piecewise interpolated between KEYS with smoothstep weights (C1 at
keyframes, wrapping over midnight); directions are analytic.
"""
from __future__ import annotations

import math
import re
from dataclasses import dataclass

from ..core.errors import VoxelError

TILT = 20.0  # degrees the sun's orbit plane leans towards -y

# hours: ambient, direct, u, zenith, horizon, sun colour, moon colour, stars (0..1)
KEYS = (
    (0.0, (0.035, 0.045, 0.09), (0.10, 0.12, 0.20), 0.0,
     (0.005, 0.008, 0.025), (0.02, 0.03, 0.06), (1.0, 0.45, 0.2), (0.75, 0.8, 0.95), 1.0),
    (4.5, (0.035, 0.045, 0.09), (0.08, 0.10, 0.16), 0.0,
     (0.005, 0.008, 0.025), (0.03, 0.035, 0.07), (1.0, 0.45, 0.2), (0.75, 0.8, 0.95), 1.0),
    (6.0, (0.20, 0.16, 0.16), (0.02, 0.01, 0.0), 0.2,
     (0.12, 0.16, 0.32), (0.95, 0.50, 0.25), (1.0, 0.55, 0.25), (0.75, 0.8, 0.95), 0.2),
    (7.5, (0.32, 0.32, 0.36), (0.75, 0.60, 0.42), 0.55,
     (0.25, 0.45, 0.80), (0.75, 0.75, 0.80), (1.0, 0.85, 0.65), (0.75, 0.8, 0.95), 0.0),
    (12.0, (0.38, 0.42, 0.50), (1.00, 0.95, 0.85), 0.8,
     (0.20, 0.42, 0.85), (0.65, 0.78, 0.95), (1.0, 0.97, 0.90), (0.75, 0.8, 0.95), 0.0),
    (16.5, (0.34, 0.34, 0.38), (0.85, 0.70, 0.50), 0.6,
     (0.24, 0.43, 0.80), (0.78, 0.74, 0.72), (1.0, 0.85, 0.60), (0.75, 0.8, 0.95), 0.0),
    (18.0, (0.20, 0.15, 0.16), (0.02, 0.01, 0.0), 0.2,
     (0.12, 0.14, 0.30), (0.98, 0.45, 0.20), (1.0, 0.50, 0.20), (0.75, 0.8, 0.95), 0.2),
    (19.5, (0.035, 0.045, 0.09), (0.08, 0.10, 0.16), 0.0,
     (0.005, 0.008, 0.025), (0.03, 0.035, 0.07), (1.0, 0.45, 0.2), (0.75, 0.8, 0.95), 1.0),
)
NAMES = {"midnight": 0.0, "dawn": 6.0, "morning": 7.5, "noon": 12.0,
         "afternoon": 16.5, "dusk": 18.0, "night": 21.0}

Vec = tuple[float, float, float]


@dataclass(frozen=True)
class DayParams:
    hours: float
    sun_dir: Vec
    moon_dir: Vec
    light_dir: Vec
    ambient: Vec
    direct: Vec
    u: float
    zenith: Vec
    horizon: Vec
    sun_color: Vec
    moon_color: Vec
    stars: float

    @property
    def sun_height(self) -> float:
        """sin(elevation) of the sun: > 0 by day."""
        return self.sun_dir[2]


def sun_direction(hours: float) -> Vec:
    a = (hours % 24.0 - 6.0) / 24.0 * 2.0 * math.pi  # 0 at sunrise, pi/2 at noon
    t = math.radians(TILT)
    return (math.cos(a), -math.sin(a) * math.sin(t), math.sin(a) * math.cos(t))


def _mix(a, b, w):
    if isinstance(a, tuple):
        return tuple(x + (y - x) * w for x, y in zip(a, b))
    return a + (b - a) * w


def at(hours: float) -> DayParams:
    """The day parameters at `hours` (any float; wraps at 24)."""
    h = float(hours) % 24.0
    keys = KEYS + ((KEYS[0][0] + 24.0,) + KEYS[0][1:],)
    for k0, k1 in zip(keys, keys[1:]):
        if k0[0] <= h <= k1[0]:
            break
    t = (h - k0[0]) / (k1[0] - k0[0])
    w = t * t * (3.0 - 2.0 * t)
    amb, direct, u, zen, hor, sunc, moonc, stars = (_mix(a, b, w) for a, b in zip(k0[1:], k1[1:]))
    sun = sun_direction(h)
    moon = (-sun[0], -sun[1], -sun[2])
    return DayParams(h, sun, moon, sun if sun[2] >= 0.0 else moon, amb, direct, u,
                     zen, hor, sunc, moonc, stars)


_HHMM = re.compile(r"^\s*(\d{1,2}):(\d{2})\s*$")


def parse_time(text: str) -> float:
    """'HH:MM' (00:00..24:00) -> hours as float. Also accepts names in NAMES."""
    s = str(text).strip().lower()
    if s in NAMES:
        return NAMES[s]
    m = _HHMM.match(s)
    if m:
        hh, mm = int(m.group(1)), int(m.group(2))
        if mm < 60 and (hh < 24 or (hh == 24 and mm == 0)):
            return (hh + mm / 60.0) % 24.0
    raise VoxelError(f"bad time of day {text!r}: expected HH:MM between 00:00 and 24:00")
