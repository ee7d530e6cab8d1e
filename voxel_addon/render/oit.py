"""Weighted blended order-independent transparency (McGuire & Bavoil 2013, JCGT 2(2)):
the cheaper alternative to depth peeling for the blend pass (Settings.transparency).

One forward-shaded geometry pass over the blend part (block.frag with OIT, shading
from include/shade.glsl) adds into an accumulation target and a revealage target
(targets.Targets: accum, reveal, with the opaque G-buffer depth attached), depth-tested
against the opaque depth without writing it; a resolve pass (oit_resolve.frag, per
sample under MSAA) turns them into one premultiplied layer, which the composite blends
like a single peel layer. The weight and the additive revealage are explained in
shaders/block.frag.
"""
from __future__ import annotations

from .passes import GeometryPass, Pass, Transparency


class OIT(Transparency):
    """One forward pass accumulates the visible blend part (ONE, ONE blending into
    targets cleared to 0: nothing covers yet), a fullscreen pass resolves it into the
    first layer target, which the composite blends as one layer."""
    layers = 1

    def __init__(self, accumulate: GeometryPass, resolve: Pass):
        self.accumulate, self.resolve = accumulate, resolve

    def shade(self, view, stats):
        self.accumulate.draw(view, stats)
        self.resolve.run()

    def programs(self):
        return self.accumulate.programs() + [self.resolve.prog]
