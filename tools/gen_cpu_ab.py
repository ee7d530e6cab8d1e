"""Generation CPU per chunk, old tree vs this one, alternating in fresh processes (issue 29).

    python tools/gen_cpu_ab.py OLD_TREE [--backend opencl|numpy] [--rounds 3]

OLD_TREE: a checkout of the other revision (`git worktree add /tmp/base 5ce3dff`). Each
round runs the measurement once in each tree (same venv, this interpreter), a new process
each; a run reports, per key set (the bench's `generation` area sets), the best of a few
generate() calls in process CPU ms per chunk (all threads: pocl's too), which the shared
machine's load moves far less than wall time. Prints each round and the median ratios.
Both trees' default Overworld: the newest version each knows (what a new world gets)."""
from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
from pathlib import Path

RUN = r'''
import json, sys, time
from voxel_addon.generation import make_generator
BIOMES = {"coast+forest": (-8, -20, 8, -4), "desert": (250, -156, 262, -144),
          "mountains": (292, -214, 304, -202), "ocean": (-40, -40, -30, -30)}
def keys(w, n):
    return [(x, y) for y in range(w[1], w[3]) for x in range(w[0], w[2])][:n]
def cpu(g, ks, reps):
    g.generate(ks[:4])
    best = 1e9
    for _ in range(reps):
        t = time.process_time(); g.generate(ks); best = min(best, time.process_time() - t)
    return 1000 * best / len(ks)
be = sys.argv[1]
g = make_generator("overworld", 7, None, be)
cl = be == "opencl"
out = {"all": cpu(g, keys((-8, -8, 8, 8), 256) if cl else keys((0, 0, 8, 4), 24), 3 if cl else 2)}
for n, w in BIOMES.items():
    out[n] = cpu(g, keys(w, 128 if cl else 8), 3 if cl else 2)
print(json.dumps(out))
'''


def run(tree: Path, backend: str) -> dict:
    env = dict(os.environ, PYTHONPATH=str(tree))
    r = subprocess.run([sys.executable, "-c", RUN, backend], cwd=tree, env=env,
                       capture_output=True, text=True, check=True)
    return json.loads(r.stdout.strip().splitlines()[-1])


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("old", type=Path)
    ap.add_argument("--backend", default="opencl", choices=["opencl", "numpy"])
    ap.add_argument("--rounds", type=int, default=3)
    a = ap.parse_args()
    new = Path(__file__).resolve().parent.parent
    ratios: dict = {}
    for i in range(a.rounds):
        b, n = run(a.old, a.backend), run(new, a.backend)
        print(f"round {i + 1}: old {b}\n         new {n}", flush=True)
        for k in b:
            ratios.setdefault(k, []).append(b[k] / n[k])
    for k, r in ratios.items():
        print(f"{k:14s} x{statistics.median(r):.2f} faster ({min(r):.2f}-{max(r):.2f})")


if __name__ == "__main__":
    main()
