"""A physically based sky: Nishita single scattering (Rayleigh, Mie, ozone absorption)
in a spherical atmosphere, the model behind Blender's Sky Texture (Nishita et al. 1993;
constants as Bruneton's "Precomputed Atmospheric Scattering", 2017 version).

Everything is relative to the light body's irradiance outside the atmosphere (1 per
RGB channel, measured on a surface facing the body), in linear RGB:
- `scatter(dirs, body)`: the Rayleigh and Mie in-scattered radiance towards an observer
  at sea level from directions `dirs`, without the phase functions (so a caller can
  apply them per pixel: the Mie peak around the sun is too sharp for any table);
- `radiance(dirs, body)`: the same with the phases applied;
- `transmittance(body)`: what reaches the ground of the body's direct light;
- `irradiance(body)`: the sky's light on an upward surface (the ambient of eq. 4.1 is
  that over pi).
The moon is the same model with the moon's irradiance (MOON of the sun's) and a cool
tint (light.daytime, render.sky). Directions are world unit vectors, z up.
"""
from __future__ import annotations

import math

import numpy as np

R_GROUND = 6360e3          # m
R_TOP = 6460e3             # 100 km: the thin air above 60 km is what dusk light reaches
BETA_R = np.array([5.802e-6, 13.558e-6, 33.1e-6])  # Rayleigh scattering, 1/m (RGB)
H_R = 8000.0
BETA_M = 3.996e-6          # Mie scattering
EXT_M = 4.40e-6            # Mie extinction
H_M = 1200.0
G_M = 0.8                  # Mie anisotropy (Cornette-Shanks)
BETA_O = np.array([0.650e-6, 1.881e-6, 0.085e-6])  # ozone absorption: the blue of dusk
O_MID, O_HALF = 25e3, 15e3  # ozone tent profile
OBSERVER = 50.0            # m above sea level
SUN_HALF_ANGLE = math.radians(0.27)
MOON = 2.5e-6              # full moon's irradiance relative to the sun's

VIEW_STEPS = 32


def phase_r(cos):
    return 3.0 / (16.0 * math.pi) * (1.0 + cos * cos)


def phase_m(cos, g: float = G_M):
    g2 = g * g
    return (3.0 / (8.0 * math.pi) * (1.0 - g2) * (1.0 + cos * cos)
            / ((2.0 + g2) * np.power(1.0 + g2 - 2.0 * g * cos, 1.5)))


def _densities(h):
    """(Rayleigh, Mie, ozone) relative densities at altitudes h (m), each h's shape."""
    h = np.maximum(h, 0.0)  # points of rays through the earth (zeroed by the caller)
    return (np.exp(-h / H_R), np.exp(-h / H_M),
            np.maximum(0.0, 1.0 - np.abs(h - O_MID) / O_HALF))


def _extinction(h):
    r, m, o = _densities(h)
    return r[..., None] * BETA_R + (m * EXT_M)[..., None] + o[..., None] * BETA_O


def _exit(p, d, radius):
    """Distance along d from points p (inside the sphere) to the sphere of `radius`."""
    b = np.einsum("...k,...k->...", p, d)
    c = np.einsum("...k,...k->...", p, p) - radius * radius
    return -b + np.sqrt(np.maximum(b * b - c, 0.0))


def _hits_ground(p, d):
    b = np.einsum("...k,...k->...", p, d)
    c = np.einsum("...k,...k->...", p, p) - R_GROUND * R_GROUND
    return (b < 0.0) & (b * b - c > 0.0), -b - np.sqrt(np.maximum(b * b - c, 0.0))


# The transmittance to the top of the atmosphere as a table over (altitude, direction)
# in Bruneton's parametrisation (dense where rays graze the horizon, the paths of
# dusk light): computed once per process (~0.2 s), 128 steps per ray.
T_SIZE = (64, 256)  # altitude, direction
_H = math.sqrt(R_TOP ** 2 - R_GROUND ** 2)
_T = None


def _to_top(r, mu):
    return np.maximum(0.0, -r * mu + np.sqrt(np.maximum(r * r * (mu * mu - 1.0) + R_TOP ** 2, 0.0)))


def _table():
    global _T
    if _T is None:
        xr = np.linspace(0.0, 1.0, T_SIZE[0])
        xm = np.linspace(0.0, 1.0, T_SIZE[1])
        rho = _H * xr[:, None]
        r = np.sqrt(rho * rho + R_GROUND ** 2)
        dmin, dmax = R_TOP - r, rho + _H
        d = dmin + xm[None, :] * (dmax - dmin)
        mu = np.where(d == 0.0, 1.0, (_H * _H - rho * rho - d * d) / np.maximum(2.0 * r * d, 1e-9))
        mu = np.clip(mu, -1.0, 1.0)
        n = 128
        s = (np.arange(n) + 0.5) / n
        dist = d[..., None] * s                                           # (R, M, n)
        h = np.sqrt(dist * dist + 2.0 * r[..., None] * mu[..., None] * dist
                    + r[..., None] ** 2) - R_GROUND
        r_, m_, o_ = (x.sum(-1) * (d / n) for x in _densities(h))       # (R, M) each
        _T = np.exp(-(r_[..., None] * BETA_R + (m_ * EXT_M)[..., None] + o_[..., None] * BETA_O))
    return _T


def _lookup(r, mu):
    """Table transmittance (..., 3) from radius r along cos-zenith mu (above the horizon)."""
    T = _table()
    rho = np.sqrt(np.maximum(r * r - R_GROUND ** 2, 0.0))
    d = _to_top(r, mu)
    dmin, dmax = R_TOP - r, rho + _H
    xm = np.clip((d - dmin) / np.maximum(dmax - dmin, 1e-9), 0.0, 1.0) * (T_SIZE[1] - 1)
    xr = np.clip(rho / _H, 0.0, 1.0) * (T_SIZE[0] - 1)
    i, j = np.minimum(xr.astype(int), T_SIZE[0] - 2), np.minimum(xm.astype(int), T_SIZE[1] - 2)
    fi, fj = (xr - i)[..., None], (xm - j)[..., None]
    return ((T[i, j] * (1 - fj) + T[i, j + 1] * fj) * (1 - fi)
            + (T[i + 1, j] * (1 - fj) + T[i + 1, j + 1] * fj) * fi)


def _sun_transmittance(p, body):
    """Transmittance (..., 3) from points p (..., 3) to the top of the atmosphere
    towards `body`; the earth's shadow softened over the body's disc."""
    r = np.linalg.norm(p, axis=-1)
    mu = np.einsum("...k,k->...", p, body) / r
    dip = -np.sqrt(np.maximum(0.0, 1.0 - (R_GROUND / r) ** 2))  # cos-zenith of the horizon
    lit = np.clip((mu - dip) / (2.0 * SUN_HALF_ANGLE) + 0.5, 0.0, 1.0)
    return _lookup(r, np.maximum(mu, dip)) * lit[..., None]


def scatter(dirs, body) -> tuple[np.ndarray, np.ndarray]:
    """(Rayleigh, Mie) single-scattered radiance without phase, each (n, 3), seen from
    sea level along unit directions dirs (n, 3) under a body of irradiance 1 in
    direction `body`. Directions below the horizon end at the ground."""
    dirs = np.asarray(dirs, float).reshape(-1, 3)
    body = np.asarray(body, float)
    body = body / np.linalg.norm(body)
    o = np.array([0.0, 0.0, R_GROUND + OBSERVER])
    p0 = np.broadcast_to(o, dirs.shape)
    t = _exit(p0, dirs, R_TOP)
    ground, tg = _hits_ground(p0, dirs)
    t = np.where(ground, tg, t)
    # denser near the observer, where the air is
    edges = (np.arange(VIEW_STEPS + 1) / VIEW_STEPS) ** 2
    mid = 0.5 * (edges[1:] + edges[:-1])
    dt = (edges[1:] - edges[:-1])[None, :] * t[:, None]          # (n, S)
    q = p0[:, None, :] + dirs[:, None, :] * (mid[None, :] * t[:, None])[..., None]
    h = np.linalg.norm(q, axis=-1) - R_GROUND                      # (n, S)
    ext = _extinction(h) * dt[..., None]                            # (n, S, 3)
    view = np.exp(-(np.cumsum(ext, axis=1) - 0.5 * ext))            # to each sample's middle
    sun = _sun_transmittance(q, body)                               # (n, S, 3)
    r, m, _ = _densities(h)
    w = view * sun * dt[..., None]
    return (w * r[..., None]).sum(1) * BETA_R, (w * m[..., None]).sum(1) * BETA_M


def radiance(dirs, body) -> np.ndarray:
    """Single-scattered sky radiance (n, 3) towards unit directions dirs under a body
    of irradiance 1 (no multiple scattering: see `MULTIPLE`)."""
    dirs = np.asarray(dirs, float).reshape(-1, 3)
    body = np.asarray(body, float) / np.linalg.norm(body)
    lr, lm = scatter(dirs, body)
    c = dirs @ body
    return phase_r(c)[:, None] * lr + phase_m(c)[:, None] * lm


def transmittance(body) -> np.ndarray:
    """(3,) fraction of the body's direct light that reaches the ground."""
    o = np.array([0.0, 0.0, R_GROUND + OBSERVER])
    return _sun_transmittance(o[None], np.asarray(body, float) / np.linalg.norm(body))[0]


def _hemisphere(n_el: int = 10, n_az: int = 24):
    """Directions over the upper hemisphere and their cos-weighted solid angles."""
    el = (np.arange(n_el) + 0.5) / n_el * (math.pi / 2)
    az = (np.arange(n_az) + 0.5) / n_az * 2 * math.pi
    e, a = np.meshgrid(el, az, indexing="ij")
    dirs = np.stack([np.cos(e) * np.cos(a), np.cos(e) * np.sin(a), np.sin(e)], -1).reshape(-1, 3)
    w = (np.sin(e) * np.cos(e) * (math.pi / 2 / n_el) * (2 * math.pi / n_az)).ravel()
    return dirs, w


_HEMI = _hemisphere()


def irradiance(body) -> np.ndarray:
    """(3,) the sky's irradiance on an upward surface at sea level (no direct light)."""
    dirs, w = _HEMI
    return (radiance(dirs, body) * w[:, None]).sum(0)


# Light scattered more than once, approximated as isotropic: this fraction of the
# single-scattered sky's irradiance over pi, added in every direction. It keeps the
# earth's shadow at dusk a dim blue instead of black and softens single scattering's
# over-saturated horizon (Bruneton's full model puts 20-50 % of the sky's light there).
MULTIPLE = 0.35


def luminance(rgb) -> np.ndarray:
    return np.asarray(rgb, float) @ np.array([0.2126, 0.7152, 0.0722])
