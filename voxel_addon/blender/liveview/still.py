"""Frames from a camera into images (Render Voxel View, Render Voxel Animation): the
pipeline on the live view's device, in an operator or a script, background mode too."""
from __future__ import annotations

import time

import numpy as np

from . import host


class Still:
    """Renders the pipeline for a camera into (h, w, 3) images."""

    def __init__(self, settings=None):
        from ...render import Settings
        from ...render.pipeline import Renderer
        self.settings = settings or Settings()
        self.r = Renderer(host.device(), self.settings)
        self._area = None       # (Area, method) to show from the next frame on
        self.ms = 0.0           # wall time of the last frame

    def set_area(self, area, method: str = "greedy") -> None:
        """What to show: a render.source.Area (meshed at the next frame)."""
        self._area = (area, method)

    def set_far(self, meshes) -> None:
        """The far tiles to draw (far.mesh.FarMeshes; Settings.far > 0): instead of
        those shown."""
        keys = {m.key for m in meshes}
        self.r.remove_far([k for k in self.r.far.tiles if k not in keys])
        self.r.update_far(meshes)

    def render(self, camera, hours: float, size) -> np.ndarray:
        """A frame as an (h, w, 3) uint8 image, row 0 = top."""
        t0 = time.perf_counter()
        with host.kept():
            if self._area is not None:
                a, method = self._area
                self.r.set_area(a.blocks, a.light, a.cx0, a.cy0, ring=True, method=method,
                                light_at=a.light_at, data=a.data)
                self.r.set_models(getattr(a, "models", None) or {})
                if a.palette is not None:
                    self.r.set_palette(a.palette)
                self._area = None
            img = self.r.render(camera, hours, (int(size[0]), int(size[1])))
        self.ms = (time.perf_counter() - t0) * 1e3
        return img

    def release(self) -> None:
        if self.r is not None:
            self.r.release()
            self.r = None


def image_pixels(img: np.ndarray) -> np.ndarray:
    """(h, w, 3) uint8, row 0 = top -> the flat float RGBA Blender's Image.pixels
    takes (row 0 = bottom)."""
    h, w = img.shape[:2]
    rgba = np.ones((h, w, 4), np.float32)
    rgba[..., :3] = img[::-1] / np.float32(255.0)
    return rgba.ravel()
