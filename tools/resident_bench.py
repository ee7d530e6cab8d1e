"""Resident memory of a streamed view, part by part, and the CPU cost of the chunk
accessors that meshing, light and edits use on cold (packed) chunks (issue 29).

    PYTHONPATH=TREE .venv/bin/python tools/resident_bench.py parts [VIEW]
    PYTHONPATH=TREE .venv/bin/python tools/resident_bench.py access

Run each against another tree too (PYTHONPATH=that tree), alternating, several
rounds: `parts` prints the bench's `resident_bytes_per_voxel` (RSS growth / active
voxels after streaming VIEW, default 32) and the arrays each chunk keeps; `access`
prints process CPU per call in us (best of 7) on 25 generated, lit chunks.
"""
from __future__ import annotations

import gc
import os
import sys
import tempfile
import time

import numpy as np


def _nbytes(x) -> int:
    if x is None:
        return 0
    if isinstance(x, tuple):  # pack_layers' tuples (earlier trees)
        return x[-1].nbytes
    return x.nbytes


def parts(view: int) -> None:
    import psutil

    from voxel_addon.bench.world import _stream, _warm
    from voxel_addon.core import chunk as C
    from voxel_addon.world import World
    tmp = tempfile.mkdtemp()
    _warm(tmp + "/warm.sqlite")
    proc = psutil.Process()
    gc.collect()
    rss0 = proc.memory_info().rss
    w = World.create(tmp + "/w.sqlite", seed=7)
    s, _, cpu = _stream(w, view)
    gc.collect()
    voxels = len(w.chunks) * C.VOLUME
    print(f"resident_bytes_per_voxel {(proc.memory_info().rss - rss0) / voxels:.3f} "
          f"({len(w.chunks)} chunks, stream CPU {cpu:.1f} s)")
    got: dict = {}
    for c in w.chunks.values():
        for name, x in (("blocks: hot arrays", getattr(c, "_blocks", None)),
                        ("blocks: packed", getattr(c, "_bpack", None)),
                        ("light: hot arrays", getattr(c, "_light", None)),
                        ("light: packed", getattr(c, "_lpack", None)),
                        ("small data", c.data)):
            got[name] = got.get(name, 0) + _nbytes(x)
        if c.mesh is not None:
            for f in ("vertices", "quads", "ranges", "colors"):
                got["mesh " + f] = got.get("mesh " + f, 0) + _nbytes(getattr(c.mesh, f, None))
    for name, n in got.items():
        print(f"  {name:20s} {n / voxels:.3f} B/voxel")
    print(f"  {'sum':20s} {sum(got.values()) / voxels:.3f} B/voxel")
    s.close()
    os._exit(0)  # (closing saves the world: not measured here)


def access() -> None:
    from voxel_addon.core import chunk as C
    from voxel_addon.generation import make_generator
    from voxel_addon.light import region_light
    C.HOT_S = -1.0  # compact() packs whatever was read
    keys = [(x, y) for y in range(7) for x in range(7)]
    region = C.paste(zip(keys, make_generator("overworld", 2019, None, "numpy").generate(keys)),
                     0, 0, 7, 7)
    lit = region_light(region, tile=5, backend="numpy")
    inner = [(np.asfortranarray(region[16 * i + 16:16 * i + 32, 16 * j + 16:16 * j + 32]),
              np.asfortranarray(lit[16 * i:16 * i + 16, 16 * j:16 * j + 16]))
             for j in range(5) for i in range(5)]

    def cold():
        out = []
        for i, (b, l) in enumerate(inner):
            c = C.Chunk((i, 0), b.copy(order="F"))
            c.light = l.copy(order="F")
            c.compact()
            out.append(c)
        return out

    def cpu(f) -> float:
        best = 1e9
        for _ in range(7):
            cs = cold()
            t = time.process_time()
            for c in cs:
                f(c)
            best = min(best, time.process_time() - t)
        return best / len(inner) * 1e6

    buf = np.zeros((60, 60, 256), np.uint16, order="F")
    a = slice(None)

    def relight(c):
        c.light = inner[0][1]
        c.compact()

    def reblock(c):
        c.blocks = inner[0][0]
        c.compact()

    rows = {
        "blocks (rebuild)": lambda c: c.blocks,
        "light (rebuild)": lambda c: c.light,
        "blocks_into chunk": lambda c: c.blocks_into(buf[20:36, 4:20], a, a, 0, 256),
        "blocks_into column": lambda c: c.blocks_into(buf[0:1, 0:16], slice(15, 16), a, 0, 256),
        "light_into 13x16x35": lambda c: c.light_into(buf[0:13, 0:16, 60:95], slice(3, 16), a,
                                                      60, 95),
        "compact light": relight,
        "compact blocks": reblock,
    }
    print(" | ".join(f"{k} {cpu(f):.1f}" for k, f in rows.items()))


if __name__ == "__main__":
    if sys.argv[1:2] == ["parts"]:
        parts(int(sys.argv[2]) if len(sys.argv) > 2 else 32)
    elif sys.argv[1:2] == ["access"]:
        access()
    else:
        sys.exit(__doc__)
