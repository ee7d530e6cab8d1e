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

from .programs import set_uniforms as _set


def targets(ctx, size, ms: int, depth) -> dict:
    """Accum (RGBA16F) and revealage (R16F) with the opaque depth attached, sampled
    like the G-buffer (ms samples when ms > 1)."""
    n = ms if ms > 1 else 0
    acc = ctx.texture(size, 4, dtype="f2", samples=n)
    rev = ctx.texture(size, 1, dtype="f2", samples=n)
    fbo = ctx.framebuffer([acc, rev], depth)
    fbo.depth_mask = False  # tested against the opaque depth, never written (nor cleared)
    return {"accum": acc, "reveal": rev, "fbo": fbo}


def draw(r, T: dict, out_fbo, mask, defs: dict, common: dict, sp: dict, stats: dict,
         mvp, shadows: bool) -> None:
    """Accumulate the visible blend part and resolve it into out_fbo (premultiplied).

    r is the Renderer; defs are the block.frag defines of the G-buffer passes plus the
    shading ones (SHADOWS, FOG, DEBUG); common/sp the deferred pass's uniforms."""
    c = r.ctx
    ms = T["ms"]
    o = T.get("oit")
    if o is None:  # made on first use: peeling frames never pay for it
        o = T["oit"] = targets(c, T["g"]["depth"].size, ms, T["g"]["depth"])
    o["fbo"].use()
    o["fbo"].clear(0, 0, 0, 0)  # accum 0, -log(revealage) 0: nothing covers yet
    prog = r.progs.get("block.vert", "block.frag", {**defs, "OIT": 1})
    r._block_uniforms(prog, mvp)
    _set(prog, **common)
    if shadows:
        T["shadow"].use(3)
        _set(prog, shadow_map=3)
    r.vol.bind(prog, 4)
    r._sky_uniforms(prog, sp)
    c.enable(c.DEPTH_TEST | c.BLEND)
    c.disable(c.CULL_FACE)
    c.blend_func = c.ONE, c.ONE
    r.geo.draw("blend", prog, mask, stats)
    c.disable(c.DEPTH_TEST | c.BLEND)
    c.blend_func = c.ONE, c.ZERO  # GL's default back

    prog = r.progs.get("fullscreen.vert", "oit_resolve.frag", {"SAMPLES": ms})
    out_fbo.use()
    o["accum"].use(0)
    o["reveal"].use(1)
    _set(prog, accum=0, reveal=1)
    r._fullscreen(prog)
