"""Real processes writing one world file at once (issue 26): every edit a process
acknowledged is in the file afterwards. Two streams of `python -m voxel_addon edit`
into the same chunk (each process rewrote the whole chunk it had loaded: 22 of 24
left), and an import racing edits into the chunks it has not reached yet (it checked
for existing chunks when it started, then overwrote them: 3 of 8 left)."""
from __future__ import annotations

import os
import subprocess
import time
from concurrent.futures import ThreadPoolExecutor

import numpy as np

from tests import host
from tests.formats import mcfiles as mc
from voxel_addon.core.blocks import REGISTRY
from voxel_addon.world import World

ENV = dict(os.environ, PYTHONPATH=str(host.ROOT), VOXEL_OPENCL="0")  # start-up: no CL probe


def cli(*args) -> subprocess.CompletedProcess:
    return subprocess.run(host.python_cmd("-m", "voxel_addon", *map(str, args)), env=ENV,
                          capture_output=True, text=True, timeout=120, cwd=host.ROOT)


def edits(world, cells):
    """Run `edit --set` for cells ((x, y, z, name)) one after the other; the cells
    whose process said it saved."""
    done = []
    for x, y, z, name in cells:
        r = cli("edit", "--world", world, "--set", x, y, z, name)
        assert r.returncode == 0, r.stderr[-2000:]
        assert "saved" in r.stdout
        done.append((x, y, z, name))
    return done


def stored(world, cells):
    with World.open(world, loader=False, readonly=True) as w:
        return [(x, y, z, n) for x, y, z, n in cells if w.get_block(x, y, z) == REGISTRY.id(n)]


def test_two_edit_processes_on_one_chunk_lose_nothing(tmp_path):
    w = tmp_path / "w.sqlite"
    with World.create(w, seed=4, generator="flat", loader=False) as world:
        world.chunk_at(15, 15)
    n = 12  # 24 edits: 22 were left before (issue 26)
    a = [(240 + i, 250, 100, "stone") for i in range(n)]
    b = [(240 + i, 252, 100, "glass") for i in range(n)]
    with ThreadPoolExecutor(2) as ex:
        fa, fb = ex.submit(edits, w, a), ex.submit(edits, w, b)
        done = fa.result() + fb.result()
    assert len(done) == 2 * n
    assert stored(w, done) == done
    with World.open(w, loader=False, readonly=True) as world:
        assert world.file.edit_count() == 2 * n


def _save(folder, w, h):
    """A save folder of w x h stone chunks (Minecraft chunks (0..w-1, 0..h-1))."""
    secs = {4: np.full((16, 16, 16), "minecraft:stone", object)}  # y 64..79 -> z 128..143
    body = mc.chunk_nbt(0, 0, secs)
    mc.write_region(folder / "region", {(x, z): body for x in range(w) for z in range(h)}, 2)


def test_an_import_racing_edits_keeps_every_edit(tmp_path):
    """Edits land in chunks the import reaches last, while it runs: each is kept
    (the chunk stays as the edit stored it, counted as kept) or re-applied."""
    # big enough that the edit processes start while it runs: regions r.0.0, r.1.0,
    # r.2.0 are read in that order, each row by row (z, then x)
    wide, side = 96, 32
    _save(tmp_path / "save", wide, side)
    w = tmp_path / "w.sqlite"
    with World.create(w, seed=0, generator="empty", loader=False):
        pass
    imp = subprocess.Popen(host.python_cmd("-m", "voxel_addon", "import", "--world", w,
                                           "--from", tmp_path / "save"),
                           env=ENV, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                           cwd=host.ROOT)
    # wait for its first batch (the import has started and passed its checks)
    t0 = time.monotonic()
    while time.monotonic() - t0 < 60 and imp.poll() is None:
        with World.open(w, loader=False, readonly=True) as world:
            if world.file.chunk_count():
                break
        time.sleep(0.05)
    # Minecraft chunk (x, z) is chunk (x, -z-1): the last ones in the file's order
    cells = [(16 * (wide - 1 - i) + 3, -16 * (side - 1) - 5, 150, "glass") for i in range(8)]
    with ThreadPoolExecutor(2) as ex:
        done = [x for f in [ex.submit(edits, w, cells[0::2]), ex.submit(edits, w, cells[1::2])]
                for x in f.result()]
    out, err = imp.communicate(timeout=120)
    assert imp.returncode == 0, err[-2000:]
    assert stored(w, done) == done
    with World.open(w, loader=False, readonly=True) as world:
        assert world.file.chunk_count() >= wide * side  # edits stored their neighbours too
        assert world.get_block(16 * 5 + 1, -16 * 5 - 1, 140) == REGISTRY.id("stone")  # imported
    print(out)


def test_overlapping_loads_generate_each_chunk_once(tmp_path):
    """Two threads loading overlapping rectangles (a stream's two workers and their
    rings): a chunk one made and has not installed yet is taken, not made again;
    both get the same blocks, with the file's edits, as a lone load."""
    import threading
    from voxel_addon.world import build
    path = tmp_path / "w.sqlite"
    with World.create(path, seed=3) as w:
        w.set_block(20, 5, 90, "glass")  # a stored edit in the shared column of chunks
    with World.open(path, loader=False) as w:
        w.file.delete_chunks()  # the edit stays: applied to the chunk made again
    with World.open(path, loader=False) as w:
        made = []
        gen, edits = w.generator.generate, w.apply_stored_edits

        raw = {}

        def generate(keys):
            made.extend(map(tuple, keys))
            out = gen(keys)
            raw.update(zip(map(tuple, keys), out))
            return out

        def slow_edits(key, blocks, data=None, **kw):  # widens the window between
            time.sleep(0.01)                           # making and installing
            return edits(key, blocks, data, **kw)
        w.generator.generate, w.apply_stored_edits = generate, slow_edits
        go = threading.Barrier(2)

        def load(cx0):
            go.wait()
            return w.load(build.keys_of(cx0, -1, cx0 + 3, 2))
        with ThreadPoolExecutor(2) as ex:
            a, b = ex.map(load, (-1, 1))  # columns of chunks 1 and 2 are shared
        assert len(made) == len(set(made)) == 15
        assert all(a[k] is b[k] for k in set(a) & set(b))
        got = {k: c.blocks.copy() for k, c in w.chunks.items()}
        assert not w._made  # nothing left behind
        glass = REGISTRY.id("glass")  # the edit went into a copy: the other load may
        assert w.chunks[(1, 0)].get(4, 5, 90) == glass != raw[(1, 0)][4, 5, 90]  # share it
    with World.open(path, loader=False) as w:
        w.file.delete_chunks()
    with World.open(path, loader=False) as w:  # each made alone
        for k, blocks in got.items():
            assert np.array_equal(w.load([k])[k].blocks, blocks), k
        assert w.get_block(20, 5, 90) == REGISTRY.id("glass")


def _lockstep(tmp_path, script, names, rounds):
    """Run SCRIPT in one process per name (argv: tmp_path, name, rounds); round i
    starts in all of them at once when tmp_path/go{i} appears; every round of every
    process must print 'rc 0' (the first failing round stops the run)."""
    procs = [subprocess.Popen(host.python_cmd("-c", script, str(tmp_path), me, str(rounds)),
                              env=ENV, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                              text=True, cwd=host.ROOT) for me in names]
    rcs = []
    try:
        for i in range(rounds):
            if any(p.stdout.readline().strip() != "ready" for p in procs):
                break
            (tmp_path / f"go{i}").touch()
            rcs.append([p.stdout.readline().strip() for p in procs])
            if set(rcs[-1]) != {"rc 0"}:
                break
    finally:
        for p in procs:
            p.kill()
    errs = [p.communicate()[1][-1500:] for p in procs]
    assert rcs == [["rc 0"] * len(procs)] * rounds, (rcs, errs)


_RACER = """
import sys, time
from pathlib import Path
from voxel_addon import cli
d, me, rounds = Path(sys.argv[1]), sys.argv[2], int(sys.argv[3])
for i in range(rounds):
    print("ready", flush=True)
    while not (d / f"go{i}").exists():
        time.sleep(0.0005)
    args = (["generate", "--seed", "4", "--generator", "flat", "--radius", "0",
             "--center", "0" if me == "a" else "16", "0"] if i % 2 == 0 else
            ["import", "--from", str(d / "m.vox"), "--at", "0" if me == "a" else "40", "0", "100"])
    rc = cli.main([*args, "--world", str(d / f"w{i}.sqlite")])
    print("rc", rc, flush=True)
"""


def test_two_processes_creating_one_world_at_once_both_succeed(tmp_path):
    """Two generates (or two .vox imports) into the same new file, started together:
    the second found a half-made file ('disk I/O error', 'already exists'), and its
    failure removed the file the first was writing, so both failed and nothing was
    kept. A new file appears whole (WorldFile.create links it in); the one that comes
    second opens it and extends it; a failing command removes only a file it made."""
    from voxel_addon.formats import vox
    grid = np.zeros((2, 2, 2), np.uint8)
    grid[0, 0, 0] = 1
    (tmp_path / "m.vox").write_bytes(vox.write(grid, np.full((256, 3), 200, np.uint8)))
    rounds = 16
    _lockstep(tmp_path, _RACER, "ab", rounds)
    for i in range(rounds):
        with World.open(tmp_path / f"w{i}.sqlite", loader=False, readonly=True) as w:
            if i % 2 == 0:
                assert sorted(w.file.chunk_keys()) == [(0, 0), (1, 0)]
            else:
                assert w.get_block(0, 0, 100) != 0 and w.get_block(40, 0, 100) != 0
    assert sorted(p.name for p in tmp_path.iterdir() if ".new" in p.name) == []


_PAINTER = """
import sys, time
from pathlib import Path
from voxel_addon import cli
d, me, rounds = Path(sys.argv[1]), sys.argv[2], int(sys.argv[3])
for i in range(rounds):
    print("ready", flush=True)
    while not (d / f"go{i}").exists():
        time.sleep(0.0005)
    rc = cli.main(["import", "--world", str(d / f"w{i}.sqlite"), "--from", str(d / f"{me}.vox"),
                   "--at", "0" if me == "red" else "40", "0", "100"])
    print("rc", rc, flush=True)
"""


def test_two_vox_imports_at_once_keep_their_colours(tmp_path):
    """Each import adds its colour to the world's palette (meta `colors`) and stores
    the index in its voxels: both added index 1 and the later palette overwrote the
    earlier, so one model took the other's colour (12 of 12 rounds). A palette built
    on a value another writer has replaced is not written (storage MetaMoved); the
    import takes its indices again from the file's palette and writes again."""
    from voxel_addon.core import colors
    from voxel_addon.formats import vox
    rounds = 8
    grid = np.ones((3, 3, 3), np.uint8)
    for me, rgb in (("red", (250, 0, 0)), ("blue", (0, 0, 250))):
        pal = np.zeros((256, 3), np.uint8)
        pal[1] = rgb
        (tmp_path / f"{me}.vox").write_bytes(vox.write(grid, pal))
    for i in range(rounds):
        with World.create(tmp_path / f"w{i}.sqlite", seed=1, generator="flat", loader=False) as w:
            w.generate_area([(x, y) for x in range(-1, 4) for y in range(-1, 2)])
    _lockstep(tmp_path, _PAINTER, ("red", "blue"), rounds)
    shown = []
    for i in range(rounds):
        with World.open(tmp_path / f"w{i}.sqlite", loader=False, readonly=True) as w:
            pal = colors.parse(w.file.meta)
            shown.append((pal[w.chunk_at(0, 0).data[1, 1, 101]].tolist(),
                          pal[w.chunk_at(2, 0).data[9, 1, 101]].tolist()))
    assert shown == [([250, 0, 0], [0, 0, 250])] * rounds, shown


_IMPORTER = """
import contextlib, io, sys, time
from pathlib import Path
from voxel_addon import cli
d, me, rounds = Path(sys.argv[1]), sys.argv[2], int(sys.argv[3])
for i in range(rounds):
    print("ready", flush=True)
    while not (d / f"go{i}").exists():
        time.sleep(0.0002)
    with contextlib.redirect_stdout(io.StringIO()):
        rc = cli.main(["import", "--world", str(d / f"w{i}.sqlite"), "--from", str(d / me)])
    print("rc", rc, flush=True)
"""

_DYES = {"red": ("x", "minecraft:desert", 0), "blue": ("z", "minecraft:jungle", 4)}


def test_two_minecraft_imports_at_once_keep_their_states_colours_and_biomes(tmp_path):
    """Each import adds its block states, dye colours, default states and biome names
    to the world's palettes (meta) and stores indices into them: both added the same
    indices and the later palettes overwrote the earlier, so one save's chunks showed
    the other's wool, logs and biome (8 of 8 rounds). A batch built on palettes another
    writer has replaced is not written (storage MetaMoved); the import maps it onto
    the file's palettes and writes again. Oracle: each save imported alone."""
    rounds = 6
    want = {}
    for me, (axis, biome, x) in _DYES.items():
        mc.dyed_save(tmp_path / me, me, axis, biome, (x,))
        with World.create(tmp_path / f"{me}.sqlite", seed=1, generator="empty",
                          loader=False) as w:
            pass
        assert cli("import", "--world", tmp_path / f"{me}.sqlite", "--from",
                   tmp_path / me).returncode == 0
        key = (x, -1)
        want[key] = mc.shown(tmp_path / f"{me}.sqlite", [key])[key]
    for i in range(rounds):
        with World.create(tmp_path / f"w{i}.sqlite", seed=1, generator="empty", loader=False):
            pass
    _lockstep(tmp_path, _IMPORTER, list(_DYES), rounds)
    bad = []
    for i in range(rounds):
        got = mc.shown(tmp_path / f"w{i}.sqlite", list(want))
        for k, (st, rgb, bio) in want.items():
            g = got[k]
            if not ((g[0] == st).all() and (g[1] == rgb).all() and (g[2] == bio).all()):
                bad.append((i, k))
    assert not bad, bad
