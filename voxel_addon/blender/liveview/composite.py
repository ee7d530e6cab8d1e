"""A frame into Blender's framebuffer (the one a POST_VIEW handler finds bound, with
the viewport's depth): colour and depth converted to Blender's projection, depth
tested LEQUAL, so Blender's objects and the voxels hide each other both ways
(shaders/viewport.frag); where the pipeline drew no surface the sky goes at the far
plane, only where Blender drew nothing.

A still region keeps its last composite (`Kept`: colour, and depth already in Blender's
projection) and redraws from it (shaders/viewport_kept.frag) while nothing that shapes
the picture changed: Blender's objects still mix by depth on every redraw."""
from __future__ import annotations

import numpy as np

from ...render.device import State

INTO_HOST = State("lequal", True, False)
KEEP = State()


class Kept:
    """A region's last composited frame at the region's size: colour (alpha 0 where
    Blender's own picture stays) and depth in Blender's projection; `look` is
    everything the picture depended on. The colour is an sRGB texture, like Blender's
    viewport framebuffer: written with the composite's decoding, read back decoded by
    the GPU, so a redraw from it decodes nothing itself (a pow per pixel was half of a
    still redraw's cost on llvmpipe)."""
    __slots__ = ("size", "color", "depth", "target", "look", "quality")

    def __init__(self, dev, size):
        self.size, self.look, self.quality = size, None, "full"
        self.color = dev.texture(size, "srgba8")
        self.depth = dev.texture(size, "r32f")
        self.target = dev.target([self.color, self.depth])

    def release(self, dev):
        dev.release(self.target, self.color, self.depth)
        self.look = None


def folds(f, size) -> bool:
    """Whether the composite does the final pass itself (Renderer.submit(f, final=False)):
    a frame at the region's SIZE (full quality), where no filtering comes between the
    final pass and the region, so folding it in changes no pixel but saves a
    full-region pass and the RGBA8 image's write and read (issue 28). A draft frame
    is smaller: its final pass stays at its size, the composite filters its output."""
    return size is not None and tuple(size) == tuple(f.color.size)


def program(dev, f, size, keep: bool):
    """viewport.frag for frame f (SIZE: the region's) and its textures: the final
    pass's inputs where folds(f, size), else its output."""
    blend = f.blend_depth
    fold = folds(f, size)
    tex = dict(f.final.tex) if fold else {"color": f.color}
    prog = dev.program("fullscreen.vert", "viewport.frag",
                       {"LAYERS": 1 if blend is not None else 0, "KEEP": int(keep),
                        "FOLD": int(fold), "DOF": "blurred" in tex})
    tex["g_depth"] = f.depth
    if blend is not None:
        tex["prev_depth"] = blend
    return prog, tex


def composite(dev, f, host_vp: np.ndarray, sky: bool, kept: Kept | None = None,
              size: tuple | None = None) -> None:
    """The prepared and submitted frame f into Blender's framebuffer (SIZE: the
    region's; f submitted without its final pass where folds(f, size)); with `kept`
    into those targets first and drawn from there."""
    prog, tex = program(dev, f, size, kept is not None)
    push = {"host_vp": np.asarray(host_vp, np.float64), "sky": bool(sky)}
    if kept is None:
        with dev.begin(None, INTO_HOST):
            dev.use(prog, tex, push)
            dev.draw()
        return
    with dev.begin(kept.target, KEEP):
        dev.use(prog, tex, push)
        dev.draw()
    draw_kept(dev, kept)


def draw_kept(dev, kept: Kept) -> None:
    """A region's kept frame into Blender's framebuffer: what composite() wrote
    there, without the pipeline (needs no frame block nor G-buffer)."""
    prog = dev.program("fullscreen.vert", "viewport_kept.frag")
    with dev.begin(None, INTO_HOST):
        dev.use(prog, {"kept_color": kept.color, "kept_depth": kept.depth})
        dev.draw()
