"""Weighted blended order-independent transparency (McGuire & Bavoil 2013, JCGT 2(2)):
the cheaper alternative to depth peeling for the blend pass (Settings.transparency).

One forward-shaded geometry pass over the blend part (block.frag with OIT, shading
from include/shade.glsl) adds into an accumulation target and a revealage target,
depth-tested against the opaque G-buffer depth without writing it; a resolve pass
(oit_resolve.frag, per sample under MSAA) turns them into one premultiplied layer,
which the composite blends like a single peel layer. The weight and the additive
revealage are explained in shaders/block.frag.
"""
from __future__ import annotations

from .passes import Pass, Transparency


def targets(ctx, size, ms: int, depth) -> dict:
    """Accum (RGBA16F) and revealage (R16F) with the opaque depth attached, sampled
    like the G-buffer (ms samples when ms > 1)."""
    n = ms if ms > 1 else 0
    acc = ctx.texture(size, 4, dtype="f2", samples=n)
    rev = ctx.texture(size, 1, dtype="f2", samples=n)
    fbo = ctx.framebuffer([acc, rev], depth)
    fbo.depth_mask = False  # tested against the opaque depth, never written (nor cleared)
    return {"accum": acc, "reveal": rev, "fbo": fbo}


class OIT(Transparency):
    """One forward pass accumulates the visible blend part, a fullscreen pass resolves
    it into the first layer target, which the composite blends as one layer."""
    layers = 1

    def __init__(self, accumulate: Pass, resolve: Pass):
        self.accumulate, self.resolve = accumulate, resolve

    def shade(self, geo, view, stats, fullscreen):
        c = self.accumulate.ctx
        self.accumulate.bind()  # clears: accum 0, -log(revealage) 0, nothing covers yet
        c.blend_func = c.ONE, c.ONE
        geo.draw(view["blend"], self.accumulate.prog, stats)
        c.blend_func = c.ONE, c.ZERO  # GL's default back
        self.resolve.run(fullscreen)

    def volume_programs(self):
        return [self.accumulate.prog]

    def programs(self):
        return [self.accumulate.prog, self.resolve.prog]
