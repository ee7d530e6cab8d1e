"""Camera matrices and region frustum culling (thesis §5.3.4), all NumPy.

World axes as SPEC §3: x, y horizontal, z up. Yaw is degrees counter-clockwise from
+x about +z, pitch degrees up. Matrices are row-major NumPy (M @ v); upload `.T`
(column-major) to GL.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


@dataclass
class Camera:
    x: float = 0.0
    y: float = 0.0
    z: float = 80.0
    yaw: float = 0.0
    pitch: float = 0.0
    fov: float = 70.0  # vertical, degrees
    aspect: float = 16 / 9
    near: float = 0.1
    far: float = 600.0

    @property
    def pos(self) -> np.ndarray:
        return np.array([self.x, self.y, self.z], np.float64)

    @property
    def forward(self) -> np.ndarray:
        y, p = math.radians(self.yaw), math.radians(self.pitch)
        return np.array([math.cos(p) * math.cos(y), math.cos(p) * math.sin(y), math.sin(p)])

    def view(self) -> np.ndarray:
        return look_at(self.pos, self.forward)

    def proj(self) -> np.ndarray:
        return perspective(self.fov, self.aspect, self.near, self.far)

    def view_proj(self) -> np.ndarray:
        return self.proj() @ self.view()


def look_at(eye, fwd, up=(0.0, 0.0, 1.0)) -> np.ndarray:
    f = np.asarray(fwd, float) / math.sqrt(float(np.dot(fwd, fwd)))
    up = np.asarray(up, float)
    if abs(f @ up) > 0.999:  # looking straight up/down: any horizontal "up" will do
        up = np.array([0.0, 1.0, 0.0]) if abs(f[1]) < 0.9 else np.array([1.0, 0.0, 0.0])
    s = _cross(f, up)
    s /= math.sqrt(float(s @ s))
    u = _cross(s, f)
    m = np.eye(4)
    m[0, :3], m[1, :3], m[2, :3] = s, u, -f
    m[:3, 3] = -m[:3, :3] @ np.asarray(eye, float)
    return m


def _cross(a, b) -> np.ndarray:  # np.cross costs ~40 µs per call on 3-vectors
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2],
                     a[0] * b[1] - a[1] * b[0]])


def perspective(fov_deg, aspect, near, far) -> np.ndarray:
    t = 1.0 / math.tan(math.radians(fov_deg) / 2)
    m = np.zeros((4, 4))
    m[0, 0], m[1, 1] = t / aspect, t
    m[2, 2] = (far + near) / (near - far)
    m[2, 3] = 2 * far * near / (near - far)
    m[3, 2] = -1.0
    return m


def ortho(l, r, b, t, n, f) -> np.ndarray:
    m = np.eye(4)
    m[0, 0], m[1, 1], m[2, 2] = 2 / (r - l), 2 / (t - b), -2 / (f - n)
    m[0, 3], m[1, 3], m[2, 3] = -(r + l) / (r - l), -(t + b) / (t - b), -(f + n) / (f - n)
    return m


_CORNERS = np.array([[i & 1, (i >> 1) & 1, (i >> 2) & 1] for i in range(8)], float)
_CLIP_CORNERS = np.c_[_CORNERS * 2 - 1, np.ones(8)]


def visible(mvp: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """Boolean mask of boxes [lo, hi] (n, 3) that may intersect the clip volume.

    A box is culled only when all 8 corners lie outside one clip plane (the thesis's
    test). Per plane only the box's most positive corner matters (centre · n +
    half-extent · |n|), so it is one (6, 6) @ (6, n) product. Planes come from the
    homogeneous clip test (-w <= x, y, z <= w), so boxes behind the camera need no
    special case.
    """
    lo, hi = np.asarray(lo, np.float64), np.asarray(hi, np.float64)
    return visible_boxes(mvp, boxes(lo, hi, np.float64))


def boxes(lo, hi, dtype=np.float32) -> np.ndarray:
    """(6, n) centres over half-extents of boxes [lo, hi], the form visible_boxes takes."""
    lo, hi = np.asarray(lo, np.float64), np.asarray(hi, np.float64)
    return np.ascontiguousarray(np.r_[(lo + hi).T * 0.5, (hi - lo).T * 0.5], dtype)


def visible_boxes(mvp: np.ndarray, ch: np.ndarray) -> np.ndarray:
    """visible() for boxes(lo, hi): the per-frame form, ~8k regions (view distance 32)
    in ~0.05 ms (the (6, n) layout is 10x faster than (n, 3) @ (3, 6) products)."""
    m = np.asarray(mvp, np.float64)
    p = np.empty((6, 4))
    p[0::2] = m[3] + m[:3]
    p[1::2] = m[3] - m[:3]
    a = np.empty((6, 6), ch.dtype)
    a[:, :3] = p[:, :3]
    a[:, 3:] = np.abs(p[:, :3])
    d = a @ ch
    d += p[:, 3:].astype(ch.dtype)
    return d.min(0) >= 0  # all six planes non-negative (one reduction, not six compares)


def frustum_corners(inv_vp: np.ndarray) -> np.ndarray:
    """The 8 world-space corners of the clip cube under inv_vp."""
    c = _CLIP_CORNERS @ inv_vp.T
    return c[:, :3] / c[:, 3:]
