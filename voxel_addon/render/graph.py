"""The passes of a frame for one set of targets and one combination of switches:
programs (compiled once per combination of defines by the device), targets and input
textures bound to each pass. The renderer keeps one graph per `Switches` until the
targets or the light volume change.

Order: shadow map -> G-buffer -> transparency geometry (peel layers) -> deferred light
-> transparency shading (peel layers lit, or OIT) -> SSAO and its blur -> composite
(sky, layers, god rays) -> distance blur -> final (thesis fig. 5.15).
"""
from __future__ import annotations

import operator
from dataclasses import dataclass

from .device import State
from .passes import Chain, GeometryPass, Pass, Peel
from . import oit

# a debug view's DEBUG define in the shaders (include/shade.glsl); "culling" draws the
# normal picture from above
DEBUG_DEFINE = {"none": 0, "albedo": 1, "normal": 2, "depth": 3, "light": 4,
                "aggregation": 5, "culling": 0}
SHADED = ("none", "culling")  # views with sky, shadows, SSAO and god rays
DEPTH_LESS = State("less", True, True)
# fullscreen passes drawn on the far plane against a coverage depth (cover.frag, or a
# one-sample peel layer's own): where it holds a surface (COVERED), where it holds none
# (SKY); COVER writes that depth
SURFACE, NO_SURFACE, COVER = State("greater", False), State("lequal", False), State("less", True)
# frame switches (and the display mode) the shading programs are built for
# (constants in them: glsl.py's CONST_name). On llvmpipe and lavapipe a shader pays
# for every branch at every pixel, whatever a uniform says: the sea, clouds or walls
# switched off cost the whole price.
FIXED = ("clouds", "cloud_shadows", "sea", "water_fx", "ssr", "walls", "ortho", "starry", "far_water",
         "display")
fixed = operator.itemgetter(*FIXED)  # a frame block's values of them (Switches.fixed)


@dataclass(frozen=True)
class Switches:
    """What decides a frame's passes and their programs."""
    samples: int         # MSAA samples (1: none)
    debug: str           # settings.DEBUG_VIEWS
    shadows: bool
    layers: int          # depth-peeling layers drawn (0 with OIT or nothing transparent)
    ssao: bool
    godrays: bool
    dof: bool
    smooth_mag: bool
    msaa_alpha: bool
    per_sample: bool
    fog: bool
    fill_holes: bool
    oit: bool
    models: bool = False  # Minecraft model quads shown (models.py): their passes too
    fixed: tuple = ()     # the frame's values of FIXED, in its order
    sky: bool = False     # the opaque layer lit in two parts by its coverage, the sky in the
                          # second (one sample, a camera inside the area, no SSAO: pipeline.py)


class Graph:
    """A frame's passes (passes.py)."""
    __slots__ = ("shadow", "g", "shade", "transparency", "post")

    def programs(self) -> list:
        return [p for x in (self.shadow, self.g, self.shade, self.transparency, *self.post)
                if x is not None for p in x.programs()]


def build(dev, T, sw: Switches, blocks, vol, walls, sprites=None) -> Graph:
    """T: targets.Targets (with what sw needs), blocks: blocktex.BlockTextures, vol:
    the light volume's texture, walls: the border columns' heights (walls.py)."""
    ms, dbg = sw.samples, DEBUG_DEFINE[sw.debug]
    cut = {"ALPHA_TEST": 1, "MSAA_ALPHA": sw.msaa_alpha}
    g = {"SAMPLES": ms, "SMOOTH_MAG": sw.smooth_mag, "DEBUG_AGG": sw.debug == "aggregation"}
    fixed = {f"CONST_{k}": int(v) for k, v in zip(FIXED, sw.fixed)}
    d = {"SAMPLES": ms, "PER_SAMPLE": sw.per_sample, "SHADOWS": sw.shadows,
         "FOG": sw.fog and sw.debug == "none", "DEBUG": dbg, **fixed}
    parts = [("opaque", {}), ("cutout", cut), ("cutout2", cut)]
    tex = blocks.bindings()
    blend = [("blend", {})]
    if sw.models:  # the stack's model quads: solid, cutout and translucent (models.py)
        parts += [("m_opaque", {"MODEL": 1}), ("m_cutout", {**cut, "MODEL": 1})]
        blend.append(("m_blend", {"MODEL": 1}))
        tex = {**tex, "mc_tex": sprites}

    def block(defines):
        return dev.program("block.vert", "block.frag", defines)

    def full(frag, defines=None):
        return dev.program("fullscreen.vert", frag, {**fixed, **(defines or {})})

    sm = {"shadow_map": T.shadow} if sw.shadows else {}

    def gbuf(x):
        return dict(g_depth=x.depth, g_albedo=x.albedo, g_normal=x.normal, light_vol=vol, **sm)

    G = Graph()
    G.shadow = GeometryPass(dev, T.shadow_fb, [
        (n, block({"SHADOW": 1, "ALPHA_TEST": n != "opaque" and n != "m_opaque",
                   "MODEL": n.startswith("m_")})) for n, _ in parts],
        DEPTH_LESS, **tex) if sw.shadows else None
    G.g = GeometryPass(dev, T.g.target, [(n, block({**g, **x})) for n, x in parts], DEPTH_LESS,
                       **tex)
    shade = {**d, "FILL_HOLES": sw.fill_holes}
    if sw.sky:  # pixels with a surface, then the others (holes, the wall, the sky, the sea)
        # (llvmpipe and lavapipe run a fullscreen pass's whole shader at every pixel)
        G.shade = Chain([
            Pass(dev, T.cover_g_fb, full("cover.frag", {"SAMPLES": ms, "FADE": 1}), COVER,
                 clear=True, g_depth=T.g.depth),
            Pass(dev, T.shaded_z, full("deferred.frag", {**shade, "COVERED": 1}), SURFACE,
                 clear=True, wall_tops=walls, tex=tex["tex"], **gbuf(T.g)),
            Pass(dev, T.shaded_z, full("deferred.frag", {**shade, "SKY": 1}), NO_SURFACE,
                 wall_tops=walls, tex=tex["tex"], **gbuf(T.g))])
    else:
        G.shade = Pass(dev, T.shaded, full("deferred.frag", shade), clear=True, wall_tops=walls,
                       tex=tex["tex"], **gbuf(T.g))
    if sw.oit:  # resolved into layer 0: the composite blends it as one peel layer
        G.transparency = oit.OIT(
            GeometryPass(dev, T.oit_fb, [(n, block({**g, **d, **x, "OIT": 1})) for n, x in blend],
                         State("less", False, False, "add"),
                         light_vol=vol, **tex, **sm),
            Pass(dev, T.layer_fb[0], full("oit_resolve.frag", {"SAMPLES": ms}),
                 accum=T.accum, reveal=T.reveal))
    else:  # no blending, the nearest remaining layer each time
        cov = T.covered  # (targets.py: a layer shaded only where it has a surface)
        zc = cov and ms == 1  # (its depth read from its copy: block.frag ZCOPY)
        layer = full("deferred.frag", {**d, "LAYER": 1, "COVERED": cov, "ZCOPY": zc}) \
            if sw.layers else None
        peel = T.peel[:sw.layers]
        G.transparency = Peel(
            [GeometryPass(dev, p.target, [(n, block({**g, **x, "PEEL": i + 1, "ZCOPY": zc}))
                                          for n, x in blend],
                          State("less", True, False), opaque_depth=T.g.depth,
                          prev_depth=T.peel[i - 1].depth if i else T.g.depth,
                          **({"opaque_normal": T.g.normal} if i == 0 else {}), **tex)
             for i, p in enumerate(peel)],
            [Pass(dev, f, layer, SURFACE if cov else State(), clear=True, ssr_color=T.opaque,
                  ssr_front=T.front, **{**gbuf(p), **({"g_depth": p.zcopy} if zc else {})})
             for f, p in zip(T.layer_zfb if cov else T.layer_fb, peel)],
            [Pass(dev, f, full("cover.frag", {"SAMPLES": ms}), COVER, clear=True, g_depth=p.depth)
             for f, p in zip(T.cover_fb, peel)] if cov and not zc else None)
    post = []
    if sw.ssao:
        post += [Pass(dev, T.ao_fb[0], full("ssao.frag"), front=T.front),
                 Pass(dev, T.ao_fb[1], full("blur.frag", {"VERTICAL": 0}), src=T.ao[0]),
                 Pass(dev, T.ao_fb[0], full("blur.frag", {"VERTICAL": 1}), src=T.ao[1])]
    # composite: sky, layers, god rays
    post.append(Pass(dev, T.comp_fb, full("composite.frag", {
        "LAYERS": G.transparency.layers, "SSAO": sw.ssao, "GODRAYS": sw.godrays,
        "SKY_DONE": sw.sky}),
        opaque=T.opaque, front=T.front, **({"ao": T.ao[0]} if sw.ssao else {}),
        **{f"layer{i}": x for i, x in enumerate(T.layers)}))
    if sw.dof:  # distance blur
        post += [Pass(dev, T.blur_fb[0], full("blur.frag", {"BILATERAL": 1, "VERTICAL": 0}),
                      src=T.comp),
                 Pass(dev, T.blur_fb[1], full("blur.frag", {"BILATERAL": 1, "VERTICAL": 1}),
                      src=T.blur[0])]
    post.append(Pass(dev, T.out_fb, full("final.frag", {"DOF": sw.dof}), sharp=T.comp,
                     **({"blurred": T.blur[1]} if sw.dof else {})))
    G.post = post
    return G
