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


def targets(ctx, size, ms: int, depth) -> dict:
    """Accum (RGBA16F) and revealage (R16F) with the opaque depth attached, sampled
    like the G-buffer (ms samples when ms > 1)."""
    n = ms if ms > 1 else 0
    acc = ctx.texture(size, 4, dtype="f2", samples=n)
    rev = ctx.texture(size, 1, dtype="f2", samples=n)
    fbo = ctx.framebuffer([acc, rev], depth)
    fbo.depth_mask = False  # tested against the opaque depth, never written (nor cleared)
    return {"accum": acc, "reveal": rev, "fbo": fbo}


def draw(r, T: dict, S: dict, P: dict, batch, stats: dict) -> None:
    """Accumulate the visible blend part (a Geometry batch) and resolve it into the
    first peel layer's target; r is the Renderer, S its passes, P its programs."""
    c = r.ctx
    with S["oit"]:
        T["oit"]["fbo"].clear(0, 0, 0, 0)  # accum 0, -log(revealage) 0: nothing covers yet
        c.blend_func = c.ONE, c.ONE
        r.geo.draw(batch, P["oit"], stats)
        c.blend_func = c.ONE, c.ZERO  # GL's default back
    with S["oit_resolve"]:
        r._fullscreen(P["oit_resolve"])
