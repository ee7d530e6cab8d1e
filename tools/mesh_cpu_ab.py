"""Greedy OpenCL meshing CPU per batch, old tree vs this one, alternating in fresh processes
(issue 29).

    python tools/mesh_cpu_ab.py OLD_TREE [--rounds 3] [--reps 15]

OLD_TREE: a checkout of the other revision (`git worktree add /tmp/base 5ce3dff`). The
bench's `meshing` inputs (the landscape's 4x4 chunks and the 8x8 `_wide` area, each
with its ring) are made once by this tree and saved, so both trees mesh the same
arrays. Each round runs the measurement once in each tree (same venv, this
interpreter), a new process each, the order swapped every round; a run reports the
median process CPU (all threads: pocl's too) of `build_chunks(..., backend="opencl")`
over REPS calls after one warm-up. Prints each round and the median ratios old / new
(> 1: this tree needs less CPU per chunk)."""
from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

MAKE = r'''
import sys, numpy as np
from voxel_addon.bench.meshing import _wide
from voxel_addon.meshing import scenes
np.savez(sys.argv[1], land=scenes.blocks("landscape"), wide=_wide(8))
'''

RUN = r'''
import json, statistics, sys, time
import numpy as np
from voxel_addon import meshing
d = np.load(sys.argv[1])
out = {}
for name in ("land", "wide"):
    a = np.asfortranarray(d[name])
    meshing.build_chunks(a, backend="opencl")
    ts = []
    for _ in range(int(sys.argv[2])):
        t = time.process_time()
        meshing.build_chunks(a, backend="opencl")
        ts.append(time.process_time() - t)
    out[name] = 1000 * statistics.median(ts)
print(json.dumps(out))
'''


def run(tree, code, *args):
    env = dict(os.environ, PYTHONPATH=str(tree))
    r = subprocess.run([sys.executable, "-c", code, *args], cwd=tree, env=env,
                       capture_output=True, text=True, check=True)
    return r.stdout.strip().splitlines()[-1] if r.stdout.strip() else ""


def main(argv=None):
    ap = argparse.ArgumentParser()
    ap.add_argument("old", type=Path)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--reps", type=int, default=15)
    a = ap.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        inp = str(Path(tmp) / "in.npz")
        run(ROOT, MAKE, inp)
        ratios = {"land": [], "wide": []}
        for r in range(a.rounds):
            trees = [("old", a.old), ("new", ROOT)]
            if r % 2:
                trees.reverse()
            got = {k: json.loads(run(t, RUN, inp, str(a.reps))) for k, t in trees}
            for n in ratios:
                ratios[n].append(got["old"][n] / got["new"][n])
            print(f"round {r + 1}: " + ", ".join(
                f"{n} {got['old'][n]:.2f} -> {got['new'][n]:.2f} ms (x{ratios[n][-1]:.2f})"
                for n in ratios), flush=True)
    for n, v in ratios.items():
        print(f"{n}: x{statistics.median(v):.2f} ({min(v):.2f}-{max(v):.2f}) chunks per CPU second")


if __name__ == "__main__":
    main()
