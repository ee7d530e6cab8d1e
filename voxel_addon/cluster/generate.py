"""`generate` on a cluster: workers generate chunks and encode their rows (the file's
own block numbering travels with the task settings); the writer commits them in
batches. A chunk with stored edits is made again by the writer, edits applied there
(World.apply_stored_edits, the one place that does it), so workers never need the
edits and an edit stored meanwhile is not lost."""
from __future__ import annotations

import time

from . import knob, tail, task_size

COMMIT = 64   # rows per transaction (or what arrived within COMMIT_S)
COMMIT_S = 1.0

_gens: dict = {}  # per worker process: (name, seed, params, backend, version) -> generator


def spec(gen, backend) -> tuple:
    """What a worker needs to make the world's generator again: its version included
    (the world's own, read by generation.for_file, not the newest)."""
    return (gen.name, gen.seed, gen.params, backend, gen.version)


def generator(spec):
    """The worker's generator for spec (made once per process)."""
    import json
    key = (spec[0], spec[1], json.dumps(spec[2], sort_keys=True), spec[3], spec[4])
    g = _gens.get(key)
    if g is None:
        from ..generation import make_generator
        g = _gens[key] = make_generator(*spec)
    return g


def make(keys, shared):
    """Worker: rows of the chunks `keys`, ready for WorldFile.save."""
    arrays = generator(shared["generator"]).generate(list(keys))
    enc = shared["encoder"]
    return [enc.row(k, b) for k, b in zip(keys, arrays)]


def run(world, pool, keys, backend=None, progress=None) -> tuple[int, int]:
    """Generate and store every key not yet in the file (nearest-first order kept
    for the tasks); returns (new chunks stored, chunks the workers computed)."""
    world.writable()
    f, gen = world.file, world.generator
    have = set(f.chunk_keys())
    todo = [k for k in keys if k not in have]
    size = pool.size  # asked once: each ask is a round trip to the scheduler
    step = task_size(len(todo), size)
    tasks, i = [], 0
    while i < len(todo):
        n = tail(len(todo) - i, step, size)
        tasks.append(tuple(todo[i:i + n]))
        i += n
    shared = {"generator": spec(gen, backend), "encoder": f.encoder()}
    buf, made, computed, t = [], 0, 0, time.monotonic()
    every = knob("COMMIT", COMMIT)

    def commit():
        nonlocal buf, made, t
        if buf:
            # decided inside the transaction: a chunk another writer stored since
            # it was planned stays theirs (as World.generate_area)
            by = {(r[0], r[1]): r for r in buf}
            made += len(f.save(buf, resolve=lambda k, v: None if f.has_chunk(k) else by[k]))
        buf, t = [], time.monotonic()
        if progress:
            progress(made, len(todo))

    try:
        for ks, rows in pool.map(make, tasks, shared=shared):
            computed += len(ks)
            for k, row in zip(ks, rows):
                if f.edits_in(k):
                    with world.gen_lock:
                        blocks = gen.generate([k])[0]
                    row = f.encode_chunk(k, *world.apply_stored_edits(k, blocks))
                buf.append(row)
            if len(buf) >= every or time.monotonic() - t > COMMIT_S:
                commit()
    finally:
        commit()  # Ctrl-C or a failed task: what arrived is kept too
    return made, computed
