"""The storage bench's cold load pass, old tree vs this one, alternating in fresh processes (issue 29).

    python tools/load_cold_ab.py OLD_TREE [--rounds 10]

OLD_TREE: a checkout of the other revision (`git worktree add /tmp/base 5ce3dff`). Each
run does what that tree's `bench --area storage --quick` does before its load row (64
overworld chunks of seed 2019 generated into a new file, the codec rows' decode passes,
the file opened read-only) and then times 6 passes of the row's loop (read_many in
batches of 32 where the tree has it, else read_chunk per key): the first is the row's
cold pass. Prints each run (us a chunk: first pass wall and process CPU, the median of
the warm ones, minor page faults of the first) and the median of the rounds' ratios
old / new. Process CPU moves less with a shared machine's load than wall time."""
from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

RUN = r'''
import resource, sys, tempfile, time
from pathlib import Path
from voxel_addon.core import chunk as C
from voxel_addon.world import World
from voxel_addon.storage import codecs, WorldFile
from voxel_addon.bench import storage as bench
path = Path(sys.argv[1]) / "storage.sqlite"
keys = [(x, y) for x in range(8) for y in range(8)]
with World.create(path, seed=2019, generator=bench._generator_name(), loader=False) as w:
    w.generate_area(keys)
    sample = [w.file.read_chunk(k)[0] for k in keys]
passes = 3 + (5 if hasattr(bench, "_cpu_best") else 0)  # the trees' codec rows
for codec in codecs.CODECS:
    blobs = [codecs.encode(codec, C.to_linear(b)) for b in sample]
    for _ in range(passes):
        for blob in blobs:
            codecs.decode(codec, blob, C.VOLUME * 2)
wf = WorldFile(path, readonly=True)
def load():
    if not hasattr(wf, "read_many"):
        for k in keys:
            wf.read_chunk(k)
        return
    for i in range(0, len(keys), 32):
        for k, got in wf.read_many(keys[i:i + 32]):
            if type(got) is not tuple:
                raise RuntimeError(f"chunk {k}: {got}")
out = []
for _ in range(6):
    f = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
    c, t = time.process_time(), time.perf_counter()
    load()
    t, c = time.perf_counter() - t, time.process_time() - c
    out.append((t, c, resource.getrusage(resource.RUSAGE_SELF).ru_minflt - f))
wf.close()
warm = sorted(c for _, c, _ in out[1:])[len(out[1:]) // 2]
n = 1e6 / len(keys)
print(out[0][0] * n, out[0][1] * n, warm * n, out[0][2])
'''


def run(tree: Path) -> list[float]:
    env = dict(os.environ, PYTHONPATH=str(tree))
    with tempfile.TemporaryDirectory() as tmp:
        got = subprocess.run([sys.executable, "-c", RUN, tmp], env=env, cwd=tmp,
                             capture_output=True, text=True)
    if got.returncode:
        sys.exit(f"{tree}: {got.stderr.strip().splitlines()[-1]}")
    return [float(v) for v in got.stdout.split()]


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("old", type=Path)
    p.add_argument("--rounds", type=int, default=10)
    a = p.parse_args()
    trees = {"old": a.old.resolve(), "new": Path(__file__).resolve().parents[1]}
    ratios: dict[str, list[float]] = {"wall": [], "cpu": [], "warm cpu": []}
    for r in range(a.rounds):
        order = list(trees) if r % 2 == 0 else list(trees)[::-1]
        got = {name: run(trees[name]) for name in order}
        for i, what in enumerate(ratios):
            ratios[what].append(got["old"][i] / got["new"][i])
        print(f"round {r + 1}: " + "  ".join(
            f"{name} first {v[0]:.1f} wall / {v[1]:.1f} cpu, warm {v[2]:.1f} cpu, "
            f"{v[3]:.0f} faults" for name, v in got.items()), flush=True)
    for what, rs in ratios.items():
        print(f"old / new, {what}: x{statistics.median(rs):.3f} "
              f"({min(rs):.2f}-{max(rs):.2f}, {len(rs)} rounds)")


if __name__ == "__main__":
    main()
