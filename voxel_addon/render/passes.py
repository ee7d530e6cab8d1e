"""The frame's passes as objects: each owns its target framebuffer, its GL switches,
its input textures at their fixed units (programs.UNITS) and its program(s).
`Renderer` builds them once per set of targets and switches (pipeline._graph) and a
frame only runs them. `Transparency` is the one interface of the blend part's two
ways: depth peeling (`Peel`, here) and weighted blended OIT (`oit.OIT`).

(moderngl's scopes would bind a pass's textures in one call, but they bind them with
a default sampler object, whose mipmap filter makes our textures incomplete.)
"""
from __future__ import annotations

from .programs import UNITS


class Pass:
    """A target, GL switches, input textures and a program; `run` binds them (and
    clears the target when asked) and draws one fullscreen triangle."""
    __slots__ = ("ctx", "fbo", "flags", "tex", "prog", "clear")

    def __init__(self, ctx, fbo, prog=None, flags: int = 0, clear: bool = False, **tex):
        self.ctx, self.fbo, self.prog, self.flags, self.clear = ctx, fbo, prog, flags, clear
        self.tex = [(t, UNITS[k]) for k, t in tex.items()]

    def bind(self) -> None:
        self.fbo.use()
        self.ctx.enable_only(self.flags)
        for t, unit in self.tex:
            t.use(unit)
        if self.clear:  # colour 0 and depth 1 (targets without depth ignore it)
            self.fbo.clear(0, 0, 0, 0, depth=1.0)

    def run(self, fullscreen) -> None:
        """fullscreen: the renderer's attribute-less triangle draw (one VAO per program)."""
        self.bind()
        fullscreen(self.prog)

    def programs(self) -> list:
        return [self.prog] if self.prog is not None else []


class GeometryPass(Pass):
    """Draws Geometry batches: `progs` is [(part name, program)] in drawing order;
    double-sided plants (cutout2) are drawn without face culling."""
    __slots__ = ("progs",)

    def __init__(self, ctx, fbo, progs, flags: int = 0, clear: bool = True, **tex):
        super().__init__(ctx, fbo, None, flags, clear, **tex)
        self.progs = progs

    @property
    def names(self) -> list[str]:
        return [name for name, _ in self.progs]

    def draw(self, geo, batches: dict, stats, shadow: bool = False) -> None:
        self.bind()
        for name, prog in self.progs:
            if name == "cutout2":
                self.ctx.disable(self.ctx.CULL_FACE)
            geo.draw(batches.get(name), prog, stats, shadow=shadow)

    def programs(self) -> list:
        return [p for _, p in self.progs]


class Transparency:
    """The blend part (water, glass): `geometry` runs before the opaque layer is shaded
    (peeling draws its G-buffers there), `shade` after it; both leave premultiplied
    layers in the layer targets, `layers` of them, which the composite blends back to
    front. `volume_programs` read the light volume's window (set per frame)."""
    layers = 0

    def geometry(self, geo, view: dict, stats) -> None:
        pass

    def shade(self, geo, view: dict, stats, fullscreen) -> None:
        pass

    def volume_programs(self) -> list:
        return []

    def programs(self) -> list:
        return []


class Peel(Transparency):
    """Depth peeling (the default: exact up to its layers): per layer a geometry pass
    into a peel G-buffer (the nearest blend surface behind the previous layer, in
    front of the opaque depth), each lit by deferred.frag (LAYER) into its layer."""

    def __init__(self, draws: list[Pass], shades: list[Pass]):
        self.draws, self.shades = draws, shades
        self.layers = len(draws)

    def geometry(self, geo, view, stats):
        for p in self.draws:
            p.bind()
            geo.draw(view["blend"], p.prog, stats)

    def shade(self, geo, view, stats, fullscreen):
        for p in self.shades:
            p.run(fullscreen)

    def volume_programs(self):
        return [p.prog for p in self.shades]

    def programs(self):
        return [p.prog for p in self.draws + self.shades]
