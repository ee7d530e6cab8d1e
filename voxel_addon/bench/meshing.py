"""Meshing bench: chunks/s per method and backend (batched `build_chunks`, and one
`quads` call per chunk), triangle counts per method on the four reference scenes beside
thesis table 6.9, bytes per vertex, region-height trade-off (cf. table 6.5)."""
from __future__ import annotations

import time

import numpy as np

from .. import meshing, opencl
from ..core import chunk
from ..core.blocks import REGISTRY, RENDERS
from ..meshing import scenes

# Thesis table 6.9: opaque / transparent triangles in thousands per method.
THESIS = {"ocean": {"none": (1611, 560), "lines": (639, 71), "squares": (553, 10), "squares_ext": (480, 9)},
          "desert": {"none": (2371, 0), "lines": (1322, 0), "squares": (1318, 0), "squares_ext": (1140, 0)},
          "landscape": {"none": (4811, 10), "lines": (2225, 2), "squares": (1992, 0), "squares_ext": (1743, 0)},
          "cave": {"none": (296, 0), "lines": (167, 0), "squares": (168, 0), "squares_ext": (147, 0)}}
BLEND = REGISTRY.render == RENDERS.index("blend")
TARGET = "target 500, goal 2000"


def _best(fn, n_chunks, reps):
    """chunks/s of the best of `reps` runs (the machine is shared: the best run is the
    least disturbed one); one warm-up run first (kernel builds, buffers)."""
    fn()
    best = min(_time(fn) for _ in range(reps))
    return n_chunks / best


def _time(fn):
    t = time.perf_counter()
    fn()
    return time.perf_counter() - t


def _wide(n):
    """n×n chunks of landscape terrain around the landscape preset (plus ring)."""
    from ..generation import make_generator
    sc = scenes.SCENES["landscape"]
    cx0, cy0 = sc.chunks[:2]
    keys = [(cx, cy) for cy in range(cy0 - 1, cy0 + n + 1) for cx in range(cx0 - 1, cx0 + n + 1)]
    gen = make_generator(scenes.GENERATOR, sc.seed, version=scenes.VERSION)
    full = chunk.paste(zip(keys, gen.generate(keys)), cx0 - 1, cy0 - 1, cx0 + n + 1, cy0 + n + 1)
    return np.asfortranarray(full[15:-15, 15:-15])


def run(ctx):
    areas = {n: scenes.blocks(n) for n in scenes.SCENES}
    backends = opencl.usable()
    best = backends[-1]
    reps = 1 if ctx.quick else 3
    land = areas["landscape"]
    n_land = ((land.shape[0] - 2) // 16) * ((land.shape[1] - 2) // 16)
    wins = [np.asfortranarray(w) for _, w in scenes.chunk_windows(land)]
    # speed, batched: one build_chunks call for the whole area (quads, regions, packing)
    for be in backends:
        for m in meshing.METHODS:
            r = _best(lambda: meshing.build_chunks(land, method=m, backend=be), n_land, reps)
            yield (f"meshing_build_chunks_per_s_{m}_{be}", r, "chunks/s",
                   f"landscape {n_land} chunks in one call, incl. regions + packing; {TARGET}")
    if not ctx.quick:
        n = 8
        wide = _wide(n)
        for be in backends:
            r = _best(lambda: meshing.build_chunks(wide, method="greedy", backend=be), n * n, 2)
            yield (f"meshing_build_chunks_per_s_greedy_{be}_wide", r, "chunks/s",
                   f"landscape {n}x{n} chunks in one call (a render distance of ~4); {TARGET}")
    # speed, one call per chunk (the plain quads() API; no packing)
    for be in backends:
        for m in meshing.METHODS:
            def one_by_one():
                for w in wins:
                    meshing.quads(w, method=m, backend=be)
            r = _best(one_by_one, len(wins), 1)
            yield (f"meshing_quads_per_s_{m}_{be}", r, "chunks/s",
                   "landscape, one quads() call per (18, 18, 256) chunk window")
    # triangles per method and scene, as the viewport draws them (region_h = REGION_H)
    counts = {}
    for name, area in areas.items():
        for m in meshing.METHODS:
            cms = meshing.build_chunks(area, method=m, backend=best)
            b = np.concatenate([c.quads["block"] for c in cms.values()])
            t = BLEND[b]
            counts[name, m] = (2 * int((~t).sum()), 2 * int(t.sum()))
        o0, t0 = counts[name, "none"]
        for m in meshing.METHODS:
            o, tr = counts[name, m]
            th = THESIS[name].get(m)
            note = (f"thesis {th[0]}k O ({100 * th[0] // THESIS[name]['none'][0]}%)" if th
                    else "thesis: n/a (greedy is new)")
            yield (f"meshing_tris_opaque_{name}_{m}", o, "triangles",
                   f"{100 * o / max(o0, 1):.0f}% of none; {note}")
            tnote = (f"thesis {th[1]}k T ({100 * th[1] // max(THESIS[name]['none'][1], 1)}%)"
                     if th and THESIS[name]["none"][1] else "")
            yield (f"meshing_tris_transparent_{name}_{m}", tr, "triangles",
                   f"{100 * tr / max(t0, 1):.0f}% of none; {tnote}")
    yield ("meshing_bytes_per_vertex", meshing.BYTES_PER_VERTEX, "B", "thesis: 6 B (8-bit coords)")
    cm = meshing.build_chunks(land, backend=best)
    yield ("meshing_bytes_per_chunk_landscape", np.mean([c.vertices.nbytes for c in cm.values()]),
           "B", "greedy, 4 vertices per quad + shared index buffer")
    # region height trade-off: triangles grow as merges are cut, draw ranges shrink
    for rh in (8, 16, 32, 64):
        r = _best(lambda: meshing.build_chunks(land, region_h=rh, backend=best), n_land, reps)
        cms = meshing.build_chunks(land, region_h=rh, backend=best).values()
        tris = sum(len(c.quads) for c in cms) * 2
        ranges = sum(int((c.ranges[..., 1] > 0).sum()) for c in cms)
        yield (f"meshing_region{rh}_triangles", tris, "triangles", f"landscape {n_land} chunks, greedy")
        yield (f"meshing_region{rh}_draw_ranges", ranges, "ranges", "non-empty (region, pass)")
        yield (f"meshing_region{rh}_chunks_per_s", r, "chunks/s", f"build_chunks, {best}")

    def draw(ax):
        names = list(areas)
        xs = np.arange(len(names))
        for k, m in enumerate(meshing.METHODS):
            ax.bar(xs + k * 0.16, [sum(counts[n, m]) / max(sum(counts[n, "none"]), 1) * 100
                                   for n in names], 0.16, label=m)
        ax.set_xticks(xs + 0.32, names)
        ax.set_ylabel("% of triangles without aggregation")
        ax.set_title("Triangles per aggregation method (cf. thesis table 6.9)")
        ax.legend()
    ctx.plot("meshing_triangles", draw)
