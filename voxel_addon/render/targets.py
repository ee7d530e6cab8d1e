"""The frame's render targets at one size: the ones every frame uses, and those of the
effects a frame needs (peel layers, SSAO, distance blur, shadows, OIT), each made the
first time a frame uses it and kept until the size or the switches that shape them
change (the viewport's defaults leave a third of them unused: ~30 MB at 1057x618)."""
from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Shape:
    """What the targets are made for."""
    size: tuple          # (w, h)
    samples: int         # MSAA samples of the G-buffers (1: none)
    shadow_size: int
    oit: bool            # weighted blended OIT's accumulation targets


COVERED = True  # (tests switch it off: the same frames the long way)


class GBuffer:
    """Depth, albedo, normal (+ glow in alpha): a geometry pass's outputs; with zcopy
    the depth again in a colour texture (a one-sample peel layer: block.frag ZCOPY)."""

    def __init__(self, dev, size, samples, zcopy: bool = False):
        self.depth = dev.texture(size, "depth", samples=samples)
        self.albedo = dev.texture(size, "rgba8", samples=samples)
        self.normal = dev.texture(size, "rgba8", samples=samples)
        self.zcopy = dev.texture(size, "r32f") if zcopy else None
        self.target = dev.target([self.albedo, self.normal, *([self.zcopy] if zcopy else [])],
                                 self.depth)

    def parts(self):
        return [self.target, self.depth, self.albedo, self.normal]


class Targets:
    def __init__(self, dev, shape: Shape):
        self.dev, self.shape = dev, shape
        size, ms = shape.size, shape.samples
        self.size, self.samples = size, ms
        self.g = GBuffer(dev, size, ms)
        self.peel: list[GBuffer] = []
        self.opaque, self.front = dev.texture(size, "rgba16f"), dev.texture(size, "rgba32f")
        self.shaded = dev.target([self.opaque, self.front])  # deferred light's outputs
        self.comp = dev.texture(size, "rgba16f")
        self.comp_fb = dev.target([self.comp])
        self.out = dev.texture(size, "rgba8")              # the final image
        self.out_fb = dev.target([self.out])
        self.layers, self.layer_fb = [], []               # shaded peel layers (OIT: one)
        # a peel layer is shaded only where it has a surface (llvmpipe and lavapipe run a
        # fullscreen pass's whole shader at every pixel, covered or not): against its
        # own depth, read from the copy its geometry pass writes, or with MSAA against a
        # one-sample depth of its coverage (cover.frag: ~4.5 ms a pass at 1057x618)
        self.covered = COVERED
        self.cover, self.cover_fb, self.layer_zfb = [], [], []
        self.cover_g = self.cover_g_fb = self.shaded_z = None  # the opaque layer's (graph.py)
        self.ao = self.ao_fb = self.blur = self.blur_fb = None
        self.shadow = self.shadow_fb = None
        self.accum = self.reveal = self.oit_fb = None
        if shape.oit:  # only while OIT is chosen: peeling frames never pay for its targets
            self.accum = dev.texture(size, "rgba16f", samples=ms)
            self.reveal = dev.texture(size, "r16f", samples=ms)
            self.oit_fb = dev.target([self.accum, self.reveal], self.g.depth)

    def need(self, layers: int, ssao: bool, dof: bool, shadows: bool, sky: bool = False) -> None:
        """Add the targets of these effects that are not made yet (sky: the opaque
        layer's coverage, graph.py)."""
        dev, size = self.dev, self.size
        if sky and self.cover_g is None:
            self.cover_g = dev.texture(size, "depth")
            self.cover_g_fb = dev.target([], self.cover_g)
            self.shaded_z = dev.target([self.opaque, self.front], self.cover_g)
        zcopy = self.covered and self.samples == 1
        while len(self.peel) < layers:
            self.peel.append(GBuffer(dev, size, self.samples, zcopy))
        while len(self.layers) < max(layers, 1 if self.shape.oit else 0):  # OIT: layer 0
            self.layers.append(dev.texture(size, "rgba16f"))
            self.layer_fb.append(dev.target([self.layers[-1]]))
        while self.covered and len(self.layer_zfb) < layers:
            i = len(self.layer_zfb)
            if not zcopy:
                self.cover.append(dev.texture(size, "depth"))
                self.cover_fb.append(dev.target([], self.cover[-1]))
            self.layer_zfb.append(dev.target([self.layers[i]],
                                             self.peel[i].depth if zcopy else self.cover[-1]))
        if ssao and self.ao is None:
            self.ao = [dev.texture(size, "r8"), dev.texture(size, "r8")]
            self.ao_fb = [dev.target([t]) for t in self.ao]
        if dof and self.blur is None:
            self.blur = [dev.texture(size, "rgba16f"), dev.texture(size, "rgba16f")]
            self.blur_fb = [dev.target([t]) for t in self.blur]
        if shadows and self.shadow is None:
            s = self.shape.shadow_size
            self.shadow = dev.texture((s, s), "depth")
            self.shadow_fb = dev.target([], self.shadow)

    @property
    def nbytes(self) -> int:
        return sum(t.nbytes for t in self._textures())

    def _textures(self):
        for x in (self.g, *self.peel):
            yield from (x.depth, x.albedo, x.normal, *([x.zcopy] if x.zcopy else []))
        for x in (self.opaque, self.front, self.comp, self.out, *self.layers, *(self.ao or ()),
                  *(self.blur or ()), *self.cover, self.cover_g, self.shadow, self.accum,
                  self.reveal):
            if x is not None:
                yield x

    def release(self) -> None:
        fbs = [self.g.target, *(p.target for p in self.peel), self.shaded, self.comp_fb,
               self.out_fb, *self.layer_fb, *self.cover_fb, *self.layer_zfb, self.cover_g_fb,
               self.shaded_z, *(self.ao_fb or ()), *(self.blur_fb or ()),
               self.shadow_fb, self.oit_fb]
        self.dev.release(*fbs)
        self.dev.release(*self._textures())
