"""CPU time of `mcres.mesh.build` (model quads of voxels with Minecraft states) per
chunk box (18×18×256, as world/models meshes a chunk with its ring), with the test
pack as the stack: the test build (tests/mcres/builds) and a 64×64 hilly terrain of
stone, grass and leaves. `--old` times the first per-quad build (tests/mcres/mesh_ref)
beside it; "ring hides" meshes the 16×16 columns inside the ring only, as
world/models does (the ring's quads were made and thrown away before). CPU time (`time.process_time`), median of RUNS: the machine may be shared.

    PYTHONPATH=$PWD .venv/bin/python tools/mesh_bench.py [--runs 5] [--old]
"""
from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))


def scenes():
    """{name: (palette, [chunk boxes (18, 18, 256) of state indices])}."""
    from tests.mcres import builds
    a = builds.build_blocks()                    # (y, z, x): block (x, y, z) → voxel (x, 15 − z, y)
    keys = sorted(set(a.reshape(-1).tolist()) - {builds.AIR})
    palette = ["", *keys]
    box = np.zeros((18, 18, 256), np.int32)
    sec = np.vectorize(lambda k: 0 if k == builds.AIR else palette.index(k))(a)
    box[1:17, 1:17, 64:80] = sec.transpose(2, 1, 0)[:, ::-1, :]
    t = builds.terrain(64)
    chunks = [t[16 * i:16 * i + 18, 16 * j:16 * j + 18] for i in range(4) for j in range(4)]
    return {"build": (palette, [box]), "terrain": (builds.TERRAIN, chunks)}


def timed(fn, runs: int) -> float:
    out = []
    for _ in range(runs):
        t = time.process_time()
        fn()
        out.append(time.process_time() - t)
    return statistics.median(out)


def main(argv=None):
    ap = argparse.ArgumentParser()
    ap.add_argument("--runs", type=int, default=5)
    ap.add_argument("--old", action="store_true")
    a = ap.parse_args(argv)
    from tests.mcres import packfiles as pf
    from voxel_addon.mcres import Resources, Stack
    from voxel_addon.mcres import mesh
    builds = {"new": mesh.build,     # and as world/models calls it: the ring only hides
              "new, ring hides": lambda *x, **k: mesh.build(*x, **k, cols=(1, 1, 17, 17))}
    if a.old:
        from tests.mcres import mesh_ref
        builds["old"] = mesh_ref.build
    with tempfile.TemporaryDirectory() as tmp:
        res = Resources(Stack.open([pf.write(Path(tmp) / "c.jar", jar=True)]))
        for name, (palette, boxes) in scenes().items():
            opaque = [np.zeros(b.shape, bool) for b in boxes]
            for kind, fn in builds.items():
                def run():
                    for b, o in zip(boxes, opaque):
                        fn(res, palette, b, o, origin=(0, 0, 0), y_min=-64)
                run()     # warm the stack's caches
                quads = sum(fn(res, palette, b, o).quads for b, o in zip(boxes, opaque))
                ms = timed(run, a.runs) * 1000 / len(boxes)
                print(f"{name:8} {kind:16}: {ms:7.2f} ms a chunk ({len(boxes)} chunks, "
                      f"{quads / len(boxes):.0f} quads a chunk)")
        res.close()


if __name__ == "__main__":
    main()
