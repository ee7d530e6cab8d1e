"""The frame's passes as objects: each owns its target, its state, its input textures
(by sampler name) and its program(s), on a device (render/device). The frame's graph
(graph.py) builds them once per set of targets and switches and a frame only runs
them. `Transparency` is the one interface of the blend part's two ways: depth peeling
(`Peel`, here) and weighted blended OIT (`oit.OIT`).
"""
from __future__ import annotations

from .device import State
from .geometry import draw


class Pass:
    """A target, a state, input textures, values and a program; `run` draws one
    fullscreen triangle (clearing the target first when asked)."""
    __slots__ = ("dev", "target", "prog", "state", "clear", "tex", "values", "when")

    def __init__(self, dev, target, prog=None, state: State = State(), clear: bool = False,
                 values: dict | None = None, **tex):
        self.dev, self.target, self.prog, self.state = dev, target, prog, state
        self.clear, self.values, self.tex = clear, values or {}, tex
        self.when = None  # a device counter: draw only where it counted samples (Peel)

    def run(self) -> None:
        with self.dev.begin(self.target, self.state, self.clear):  # (cleared in any case)
            self.dev.use(self.prog, self.tex, self.values)
            with self.dev.only_if(self.when):
                self.dev.draw()

    def programs(self) -> list:
        return [self.prog] if self.prog is not None else []


class Chain:
    """Passes that make one step of the frame, run in order."""

    def __init__(self, passes: list):
        self.passes = passes

    def run(self) -> None:
        for p in self.passes:
            p.run()

    def programs(self) -> list:
        return [x for p in self.passes for x in p.programs()]


class GeometryPass(Pass):
    """Draws Geometry batches: `progs` is [(part name, program)] in drawing order;
    double-sided plants (cutout2) are drawn without face culling."""
    __slots__ = ("progs", "count")

    def __init__(self, dev, target, progs, state: State = State(), clear: bool = True,
                 values: dict | None = None, **tex):
        super().__init__(dev, target, None, state, clear, values, **tex)
        self.progs = progs
        self.count = None  # a device counter of the samples drawn (Peel)

    @property
    def names(self) -> list[str]:
        return [name for name, _ in self.progs]

    def draw(self, batches: dict, stats, shadow: bool = False) -> None:
        dev = self.dev
        with dev.begin(self.target, self.state, self.clear), dev.only_if(self.when), \
                dev.counting(self.count):
            for name, prog in self.progs:
                b = batches.get(name)
                if not b:
                    continue
                if name == "cutout2" and self.state.cull:
                    dev.state(State(self.state.depth, self.state.write, False, self.state.blend))
                dev.use(prog, self.tex, self.values)
                draw(dev, b, stats, shadow)

    def programs(self) -> list:
        return [p for _, p in self.progs]


class Transparency:
    """The blend part (water, glass): `geometry` runs before the opaque layer is shaded
    (peeling draws its G-buffers there), `shade` after it; both leave premultiplied
    layers in the layer targets, `layers` of them, which the composite blends back to
    front."""
    layers = 0

    def geometry(self, view: dict, stats) -> None:
        pass

    def shade(self, view: dict, stats) -> None:
        pass

    def programs(self) -> list:
        return []


class Peel(Transparency):
    """Depth peeling (the default: exact up to its layers): per layer a geometry pass
    into a peel G-buffer (the nearest blend surface behind the previous layer, in
    front of the opaque depth), each lit by deferred.frag (LAYER) into its layer; with
    `covers`, each layer's coverage first (cover.frag), so the lighting runs only
    where the layer has a surface (COVERED)."""

    def __init__(self, draws: list[GeometryPass], shades: list[Pass], covers: list | None = None):
        self.draws, self.shades, self.covers = draws, shades, covers or []
        self.layers = len(draws)
        # a layer nothing was drawn into is not shaded, and the layers behind it are not
        # drawn: the second and third layers are empty in most views, and on llvmpipe
        # such a pass cost as much as a full one (bench/README.md: the H200 section).
        # Not the first: it holds what made the frame peel at all, and counting its
        # samples cost llvmpipe ~25 % of a frame without effects (a lost fast path)
        for i, (d, sh) in enumerate(zip(draws, shades)):
            if i:
                d.count = sh.when = d.dev.counter(("peel", i))
                d.when = draws[i - 1].count
                if self.covers:
                    self.covers[i].when = sh.when

    def geometry(self, view, stats):
        for p in self.draws:
            p.draw(view, stats)

    def shade(self, view, stats):
        for i, p in enumerate(self.shades):
            if self.covers:
                self.covers[i].run()
            p.run()

    def programs(self):
        return [x for p in self.draws for x in p.programs()] + [
            p.prog for p in (*self.shades, *self.covers)]
