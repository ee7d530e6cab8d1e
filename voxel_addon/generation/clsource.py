"""Compiles a lang.Program to OpenCL C: one kernel per unit, appended to gpu/gen.cl
(cl.Runner builds and runs them on batches of chunks).

Every node becomes one C statement doing exactly the float32 operation NumPy does
(execute.py); constants are written as hex floats so no decimal rounding sneaks in.

Speed on pocl: 2D kernels rely on its work-group vectorizer (see gpu/noise.h), so
they have no control flow: no early returns (domains are padded), no && || (they
branch), and loads that might be out of range are clamped and then masked. 3D
kernels run on a list of (chunk, z) layers below the pass's `top`, skip columns
above their own top, and are written as explicit 8-lane code (`_GenV`, README).
"""
from __future__ import annotations

import re

from .. import resources
from ..core import chunk as C
from .clscalar import _Gen
from .clvector import _GenV, vectorizable


def source(units, size=C.SIZE, inline: bool = False) -> str:
    """The OpenCL C of UNITS: the same text for the same program, whichever process or
    generator object made it (`_renumber`). INLINE: every noise call inlined (`called`
    not applied), for a program whose build is off the path to a picture and that runs
    big batches (the far surface: ~10 % faster per 16384 columns)."""
    g, gv, free = _Gen(units, size), _GenV(units), _GenV(units, size)
    free.free = True  # lanes that are not a row of 8 voxels: g3 and 2D units
    most = (10 ** 9,) * 2 if inline else CALLS_INLINED
    return resources.kernel("gen.cl") + _renumber("\n".join(
        called(((gv if u.kind == "3d" else free) if vectorizable(u, size) else g).kernel(i, u),
               most[u.kind == "3d"])
        for i, u in enumerate(units)))


# A kernel inlines a big noise function up to this many calls (per-column and
# lattice kernels, per-voxel 3D ones); with more it calls gen.cl's never-inlined `_c`
# twin: each inlined copy is compiled again by pocl at the kernel's first launch
# (seconds on a fresh install, issue 28), while a call costs a few instructions next
# to a noise body's ~100. The hot per-voxel kernels (3 calls) stay inlined.
CALLS_INLINED = (2, 4)
_CALLED = re.compile(r"\b(perlin2|perlin3|voronoi2|voronoi3|perlin2_8|perlin3_8|voronoi2_8)\(")


def called(text: str, most: int) -> str:
    """TEXT (one kernel) with its big noise calls made calls of the `_c` twins when it
    has more than MOST of one function."""
    n: dict = {}
    for m in _CALLED.finditer(text):
        n[m[1]] = n.get(m[1], 0) + 1
    many = {f for f, k in n.items() if k > most}
    return _CALLED.sub(lambda m: f"{m[1]}_c(" if m[1] in many else m[0], text) if many else text


_VAR = re.compile(r"\bv(\d+)\b")


def _renumber(text: str) -> str:
    """Variables v<node id> renamed v0, v1, ... in order of appearance. Node ids come
    from one counter per process (lang.E), so the same program made twice (a second
    generator, world or scene) had other names: another source, which opencl.build and
    pocl's disk cache missed, so pocl compiled it all again (seconds per generator)."""
    names: dict[str, str] = {}
    return _VAR.sub(lambda m: names.setdefault(m.group(1), f"v{len(names)}"), text)
