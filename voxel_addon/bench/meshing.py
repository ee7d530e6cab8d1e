"""Meshing bench: chunks/s per method and backend, triangle counts per method on the four
reference scenes beside thesis table 6.9, bytes per vertex, region-height trade-off (table 6.5)."""
from __future__ import annotations

import time

import numpy as np

from .. import meshing, opencl
from ..core.blocks import REGISTRY, RENDERS
from ..meshing import scenes

# Thesis table 6.9: opaque / transparent triangles in thousands per method.
THESIS = {"ocean": {"none": (1611, 560), "lines": (639, 71), "squares": (553, 10), "squares_ext": (480, 9)},
          "desert": {"none": (2371, 0), "lines": (1322, 0), "squares": (1318, 0), "squares_ext": (1140, 0)},
          "landscape": {"none": (4811, 10), "lines": (2225, 2), "squares": (1992, 0), "squares_ext": (1743, 0)},
          "cave": {"none": (296, 0), "lines": (167, 0), "squares": (168, 0), "squares_ext": (147, 0)}}
BLEND = REGISTRY.render == RENDERS.index("blend")


def _rate(windows, **kw):
    meshing.quads(windows[0], **kw)        # warm-up: kernel build, buffers
    t = time.perf_counter()
    for w in windows:
        meshing.quads(w, **kw)
    return len(windows) / (time.perf_counter() - t)


def run(ctx):
    areas = {n: scenes.blocks(n) for n in scenes.SCENES}
    backends = ["numpy"] + (["opencl"] if opencl.available() else [])
    # speed: every chunk of the landscape (quick: 4 chunks)
    wins = [w for _, w in scenes.chunk_windows(areas["landscape"])]
    wins = wins[:4] if ctx.quick else wins
    for be in backends:
        for m in meshing.METHODS:
            r = _rate(wins, method=m, backend=be)
            yield (f"meshing_chunks_per_s_{m}_{be}", r, "chunks/s",
                   f"landscape, {len(wins)} chunks with context; target 500, goal 2000")
    if "opencl" in backends:
        t = time.perf_counter()
        for w in wins:
            meshing.build_chunk(w, backend="opencl")
        yield ("meshing_build_chunk_per_s_greedy_opencl", len(wins) / (time.perf_counter() - t),
               "chunks/s", "quads + regions + packed vertices")
    # triangle counts per method and scene (whole 4x4-chunk areas, chunk by chunk)
    counts = {}
    for name, area in areas.items():
        ws = [w for _, w in scenes.chunk_windows(area)]
        for m in meshing.METHODS:
            qs = np.concatenate([meshing.quads(w, method=m, backend=backends[-1]) for w in ws])
            t = BLEND[qs["block"]]
            counts[name, m] = (2 * int((~t).sum()), 2 * int(t.sum()))
        o0, t0 = counts[name, "none"]
        for m in meshing.METHODS:
            o, tr = counts[name, m]
            th = THESIS[name].get(m)
            note = (f"thesis {th[0]}k O ({100 * th[0] // THESIS[name]['none'][0]}%), "
                    f"{th[1]}k T" if th else "thesis: n/a (greedy is new)")
            yield (f"meshing_tris_opaque_{name}_{m}", o, "triangles",
                   f"{100 * o / max(o0, 1):.0f}% of none; {note}")
            yield (f"meshing_tris_transparent_{name}_{m}", tr, "triangles",
                   f"{100 * tr / max(t0, 1):.0f}% of none")
    yield ("meshing_bytes_per_vertex", meshing.BYTES_PER_VERTEX, "B", "thesis: 6 B (8-bit coords)")
    cm = [meshing.build_chunk(w) for w in wins]
    yield ("meshing_bytes_per_chunk_landscape", np.mean([c.vertices.nbytes for c in cm]), "B",
           "greedy, 4 vertices per quad + shared index buffer")
    # region height trade-off: triangles grow as merges are cut, draw ranges shrink
    for rh in (8, 16, 32, 64):
        t = time.perf_counter()
        cms = [meshing.build_chunk(w, region_h=rh, backend=backends[-1]) for w in wins]
        dt = time.perf_counter() - t
        tris = sum(len(c.quads) for c in cms) * 2
        ranges = sum(int((c.ranges[..., 1] > 0).sum()) for c in cms)
        yield (f"meshing_region{rh}_triangles", tris, "triangles", f"landscape {len(wins)} chunks")
        yield (f"meshing_region{rh}_draw_ranges", ranges, "ranges", "non-empty (region, pass)")
        yield (f"meshing_region{rh}_chunks_per_s", len(wins) / dt, "chunks/s", backends[-1])

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
