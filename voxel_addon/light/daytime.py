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

Colours come from a physically based sky (light.atmosphere: single scattering with
ozone, the sun and, opposite it, a moon of MOON of its light with a cool tint),
already multiplied by the exposure of that hour (an eye that adapts part of the way:
dusk and night stay darker than noon but readable), so eq. 4.1's block light keeps
its meaning at every hour. They are tabulated in KEYS (made by `table()`, checked
against it by tests/light/test_daytime.py) and interpolated between keyframes with
smoothstep weights (C1 at keyframes, wrapping over midnight), so the bake's colour
ramps (blender/bake.py) reproduce `at` exactly; directions are analytic.
Run `python -m voxel_addon.light.daytime` to print a new KEYS after changing the model.
"""
from __future__ import annotations

import math
import re
from dataclasses import dataclass

from ..core.errors import VoxelError

TILT = 20.0  # degrees the sun's orbit plane leans towards -y

# What `table()` puts in KEYS (the model behind the numbers): hours of the keyframes,
# symmetric around noon (the sun's path is) and dense at dawn and dusk.
KEY_HOURS = (0.0, 3.0, 4.5, 5.0, 5.25, 5.5, 5.75, 6.0, 6.25, 6.5, 7.0, 8.0, 9.5, 12.0,
             14.5, 16.0, 17.0, 17.5, 17.75, 18.0, 18.25, 18.5, 18.75, 19.0, 19.5, 21.0)
MOON_TINT = (0.62, 0.78, 1.0)  # moonlight as films show it (the Purkinje shift)
FILL = 1.6             # sky light on faces that see more than the sky: the air around,
                       # light from terrain and leaves (eq. 4.1's ambient is one colour)
GROUND = 0.2           # albedo of the ground that bounces light back up
WHITE = 1.7            # a white flat ground at noon (AgX shows it near white)
ADAPT = 0.8            # how far the exposure follows the light: 1 full (dusk = noon), 0 none
NIGHT = (1e-5, 0.6)    # below this fraction of noon's light it follows less: night stays
                       # night (lamps stand out) while dusk stays readable

# hours: ambient, direct, u, zenith, horizon, sun colour, moon colour, stars (0..1), exposure
KEYS = (
    (0.0, (0.01145, 0.01847, 0.03384), (0.0747, 0.08631, 0.09654), 0.0, (0.00254, 0.00562, 0.01365), (0.00977, 0.01499, 0.02027), (0.0, 0.0, 0.0), (0.62, 0.78, 1.0), 1.0, 123064.0),
    (3.0, (0.01136, 0.01886, 0.03504), (0.09052, 0.10099, 0.10676), 0.0, (0.00203, 0.00496, 0.01247), (0.01219, 0.01803, 0.02302), (0.0, 0.0, 0.0), (0.62, 0.78, 1.0), 1.0, 153144.0),
    (4.5, (0.01192, 0.02043, 0.03796), (0.12472, 0.12593, 0.11321), 0.0, (0.00244, 0.00565, 0.01327), (0.0173, 0.02322, 0.02554), (0.0, 0.0, 0.0), (0.62, 0.78, 1.0), 1.0, 227659.0),
    (5.0, (0.01267, 0.02047, 0.03678), (0.13933, 0.12727, 0.09686), 0.0, (0.00283, 0.00595, 0.01311), (0.01978, 0.02402, 0.02286), (0.0, 0.0, 0.0), (0.62, 0.78, 1.0), 0.9974, 274641.0),
    (5.25, (0.05786, 0.03548, 0.04037), (0.10338, 0.08579, 0.05539), 0.0, (0.00959, 0.00751, 0.01134), (0.04221, 0.02108, 0.01617), (0.0, 0.0, 0.0), (0.62, 0.78, 1.0), 0.7966, 219452.0),
    (5.5, (0.32727, 0.16658, 0.23436), (0.00985, 0.00686, 0.00323), 0.0, (0.08052, 0.04269, 0.07023), (0.24589, 0.03926, 0.03651), (0.0, 0.0, 0.0), (0.62, 0.78, 1.0), 0.4198, 23974.3),
    (5.75, (0.70313, 0.37559, 0.55933), (0.0003, 0.00014, 3.006e-05), 0.0112, (0.24327, 0.13784, 0.23137), (0.40032, 0.07727, 0.08549), (0.0, 0.0, 0.0), (0.62, 0.78, 1.0), 0.0858, 1010.87),
    (6.0, (0.92286, 0.68495, 0.75342), (4.81395, 0.44178, 0.00256), 0.0697, (0.30461, 0.24555, 0.30819), (1.29261, 0.26358, 0.116), (1.0, 0.09177, 0.00053), (0.62, 0.78, 1.0), 0.0, 148.655),
    (6.25, (0.37672, 0.41154, 0.47724), (4.68132, 1.7454, 0.29014), 0.1664, (0.11154, 0.13872, 0.18644), (0.72778, 0.3856, 0.1283), (1.0, 0.37284, 0.06198), (0.62, 0.78, 1.0), 0.0, 32.0177),
    (6.5, (0.33081, 0.41726, 0.53909), (4.29176, 2.37608, 0.8732), 0.2872, (0.08842, 0.13302, 0.20242), (0.62452, 0.47202, 0.24238), (1.0, 0.55364, 0.20346), (0.62, 0.78, 1.0), 0.0, 21.2621),
    (7.0, (0.33061, 0.44831, 0.63399), (3.89212, 2.82583, 1.67744), 0.5458, (0.07545, 0.13111, 0.22665), (0.54459, 0.53007, 0.39477), (1.0, 0.72604, 0.43098), (0.62, 0.78, 1.0), 0.0, 15.608),
    (8.0, (0.28568, 0.38567, 0.56204), (2.69145, 2.27225, 1.73069), 0.8, (0.05446, 0.10318, 0.19554), (0.36678, 0.41209, 0.38165), (1.0, 0.84425, 0.64303), (0.62, 0.78, 1.0), 0.0, 9.61642),
    (9.5, (0.25466, 0.33303, 0.48073), (1.90589, 1.71212, 1.44166), 0.8, (0.04531, 0.08824, 0.17442), (0.25367, 0.30274, 0.30811), (1.0, 0.89833, 0.75642), (0.62, 0.78, 1.0), 0.0, 6.49544),
    (12.0, (0.24474, 0.31379, 0.44842), (1.59659, 1.46625, 1.27922), 0.8, (0.05428, 0.09546, 0.18084), (0.20856, 0.25449, 0.26856), (1.0, 0.91836, 0.80122), (0.62, 0.78, 1.0), 0.0, 5.3509),
    (14.5, (0.25466, 0.33303, 0.48073), (1.90589, 1.71212, 1.44166), 0.8, (0.04531, 0.08824, 0.17442), (0.25367, 0.30274, 0.30811), (1.0, 0.89833, 0.75642), (0.62, 0.78, 1.0), 0.0, 6.49544),
    (16.0, (0.28568, 0.38567, 0.56204), (2.69145, 2.27225, 1.73069), 0.8, (0.05446, 0.10318, 0.19554), (0.36678, 0.41209, 0.38165), (1.0, 0.84425, 0.64303), (0.62, 0.78, 1.0), 0.0, 9.61642),
    (17.0, (0.33061, 0.44831, 0.63399), (3.89212, 2.82583, 1.67744), 0.5458, (0.07545, 0.13111, 0.22665), (0.54459, 0.53007, 0.39477), (1.0, 0.72604, 0.43098), (0.62, 0.78, 1.0), 0.0, 15.608),
    (17.5, (0.33081, 0.41726, 0.53909), (4.29176, 2.37608, 0.8732), 0.2872, (0.08842, 0.13302, 0.20242), (0.62452, 0.47202, 0.24238), (1.0, 0.55364, 0.20346), (0.62, 0.78, 1.0), 0.0, 21.2621),
    (17.75, (0.37672, 0.41154, 0.47724), (4.68132, 1.7454, 0.29014), 0.1664, (0.11154, 0.13872, 0.18644), (0.72778, 0.3856, 0.1283), (1.0, 0.37284, 0.06198), (0.62, 0.78, 1.0), 0.0, 32.0177),
    (18.0, (0.65238, 0.48421, 0.5326), (3.40306, 0.3123, 0.00181), 0.0697, (0.21533, 0.17358, 0.21787), (0.91377, 0.18633, 0.08201), (1.0, 0.09177, 0.00053), (0.62, 0.78, 1.0), 0.0, 105.087),
    (18.25, (0.70313, 0.37559, 0.55933), (0.0003, 0.00014, 3.006e-05), 0.0112, (0.24327, 0.13784, 0.23137), (0.40032, 0.07727, 0.08549), (0.0, 0.0, 0.0), (0.62, 0.78, 1.0), 0.0858, 1010.87),
    (18.5, (0.32727, 0.16658, 0.23436), (0.00985, 0.00686, 0.00323), 0.0, (0.08052, 0.04269, 0.07023), (0.24589, 0.03926, 0.03651), (0.0, 0.0, 0.0), (0.62, 0.78, 1.0), 0.4198, 23974.3),
    (18.75, (0.05786, 0.03548, 0.04037), (0.10338, 0.08579, 0.05539), 0.0, (0.00959, 0.00751, 0.01134), (0.04221, 0.02108, 0.01617), (0.0, 0.0, 0.0), (0.62, 0.78, 1.0), 0.7966, 219452.0),
    (19.0, (0.01267, 0.02047, 0.03678), (0.13933, 0.12727, 0.09686), 0.0, (0.00283, 0.00595, 0.01311), (0.01978, 0.02402, 0.02286), (0.0, 0.0, 0.0), (0.62, 0.78, 1.0), 0.9974, 274641.0),
    (19.5, (0.01192, 0.02043, 0.03796), (0.12472, 0.12593, 0.11321), 0.0, (0.00244, 0.00565, 0.01327), (0.0173, 0.02322, 0.02554), (0.0, 0.0, 0.0), (0.62, 0.78, 1.0), 1.0, 227659.0),
    (21.0, (0.01136, 0.01886, 0.03504), (0.09052, 0.10099, 0.10676), 0.0, (0.00203, 0.00496, 0.01247), (0.01219, 0.01803, 0.02302), (0.0, 0.0, 0.0), (0.62, 0.78, 1.0), 1.0, 153144.0),
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
    exposure: float  # what the model's light (per unit of sun outside the air) was
                     # multiplied by to give these colours (render.sky scales the sky so)

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
    amb, direct, u, zen, hor, sunc, moonc, stars, _ = (_mix(a, b, w) for a, b in zip(k0[1:], k1[1:]))
    # the exposure varies over orders of magnitude: interpolated in log
    ex = math.exp(_mix(math.log(k0[-1]), math.log(k1[-1]), w))
    sun = sun_direction(h)
    moon = (-sun[0], -sun[1], -sun[2])
    return DayParams(h, sun, moon, sun if sun[2] >= 0.0 else moon, amb, direct, u,
                     zen, hor, sunc, moonc, stars, ex)


def _smooth(e0, e1, x):
    t = min(1.0, max(0.0, (x - e0) / (e1 - e0)))
    return t * t * (3.0 - 2.0 * t)


def key(hours: float) -> tuple:
    """One KEYS row from the sky model (light.atmosphere) at `hours`: slow (~50 ms)."""
    import numpy as np
    from . import atmosphere as A
    sun = np.array(sun_direction(hours))
    tint = np.array(MOON_TINT) / A.luminance(MOON_TINT)

    def body(d, k):  # sky irradiance, direct irradiance facing the body: times k
        return A.irradiance(d) * (1.0 + A.MULTIPLE) * k, A.transmittance(d) * k
    sky_s, dir_s = body(sun, 1.0)
    sky_m, dir_m = body(-sun, A.MOON * tint)
    up_s, up_m = max(sun[2], 0.0), max(-sun[2], 0.0)
    sky = sky_s + sky_m
    bounce = GROUND * (sky + dir_s * up_s + dir_m * up_m) * 0.5
    ambient = (sky * FILL + bounce) / math.pi
    direct = (dir_s if sun[2] >= 0.0 else dir_m) / math.pi
    # what the exposure adapts to: the ground, and walls facing a low sun (or they glare)
    ground = A.luminance(ambient + (dir_s * _facing(sun[2]) + dir_m * _facing(-sun[2])) / math.pi)
    y_noon = _noon()
    ratio = ground / y_noon
    exposure = WHITE / y_noon * ratio ** -ADAPT * min(1.0, ratio / NIGHT[0]) ** (ADAPT - NIGHT[1])
    # the sky's colours for the bake's world and the old eq. 5.1 (render.sky has them all)
    zen, hor = sky_at(hours, [(0.0, 0.0, 1.0), (-sun[1], sun[0], 0.0)], 1.0)
    sun_color = dir_s / max(dir_s.max(), 1e-9)
    u = 0.8 * _smooth(-0.1, 0.45, sun[2])
    stars = _smooth(-0.02, -0.25, sun[2])
    r = lambda v: tuple(round(float(x), 5 if abs(x) > 1e-4 else 8) for x in v)  # noqa: E731
    return (round(hours, 4), r(ambient * exposure), r(direct * exposure), round(u, 4),
            r(zen * exposure), r(hor * exposure), r(sun_color), r(MOON_TINT), round(stars, 4),
            float(f"{exposure:.6g}"))


SOFTEN = 20.0  # degrees: the sky's Rayleigh light is averaged over this much azimuth
              # each way (light scattered more than once blurs the sharp edge of the
              # earth's shadow at dusk that single scattering draws)


def sky_parts(hours: float, dirs):
    """The sky towards unit dirs (n, 3) at `hours` (sun and moon, multiple scattering
    approximated) in two parts, each (n, 3): everything but the sun's Mie scattering,
    and that without its phase function (atmosphere.phase_m of the angle to the sun),
    per unit of sunlight outside the air: what render.sky tabulates for the shader."""
    import numpy as np
    from . import atmosphere as A
    sun = np.array(sun_direction(hours))
    tint = np.array(MOON_TINT) / A.luminance(MOON_TINT)
    dirs = np.asarray(dirs, float).reshape(-1, 3)
    dirs = dirs / np.linalg.norm(dirs, axis=1, keepdims=True)
    _, m_s = A.scatter(dirs, sun)
    rest = A.MULTIPLE * (A.irradiance(sun) + A.irradiance(-sun) * A.MOON * tint) / math.pi
    for turn, w in ((-SOFTEN, 0.25), (0.0, 0.5), (SOFTEN, 0.25)):
        c, s = math.cos(math.radians(turn)), math.sin(math.radians(turn))
        d = dirs @ np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]])  # about z
        r_s, _ = A.scatter(d, sun)
        rest = rest + w * (A.phase_r(d @ sun)[:, None] * r_s + A.radiance(d, -sun) * A.MOON * tint)
    return rest, m_s


def sky_at(hours: float, dirs, exposure: float = 1.0):
    """Sky radiance (n, 3) towards unit dirs at `hours` times exposure."""
    import numpy as np
    from . import atmosphere as A
    rest, mie = sky_parts(hours, dirs)
    dirs = np.asarray(dirs, float).reshape(-1, 3)
    dirs = dirs / np.linalg.norm(dirs, axis=1, keepdims=True)
    return (rest + A.phase_m(dirs @ np.array(sun_direction(hours)))[:, None] * mie) * exposure


def _facing(z: float) -> float:
    return max(z, 0.3 * math.sqrt(max(0.0, 1.0 - z * z))) if z > 0.0 else 0.0


def _noon() -> float:
    """Luminance of a white flat ground at noon by the model (the exposure's anchor)."""
    import numpy as np
    from . import atmosphere as A
    sun = np.array(sun_direction(12.0))
    sky = A.irradiance(sun) * (1.0 + A.MULTIPLE)
    d = A.transmittance(sun)
    return float(A.luminance((sky * FILL + GROUND * (sky + d * sun[2]) * 0.5
                              + d * _facing(sun[2])) / math.pi))


def table() -> tuple:
    """KEYS from the model (what `python -m voxel_addon.light.daytime` prints)."""
    return tuple(key(h) for h in KEY_HOURS)


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


if __name__ == "__main__":
    print("KEYS = (")
    for k in table():
        print(f"    {k!r},")
    print(")")
