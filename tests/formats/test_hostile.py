"""Hostile files (issue 26): budgets instead of trust. Every case that cost minutes
or gigabytes on main goes through the real CLI in a child process and must give exit
2, one line on stderr, at most 600 MB peak RSS (the CLI process's own, see _WRAP) and 10 s,
and leave the world file as it was. The decoders' limits are checked one by one with
tracemalloc (a limit removed makes its test fail: see the mutants in the report)."""
from __future__ import annotations

import hashlib
import os
import resource
import signal
import subprocess
import sys
import threading
import time
import zlib
from pathlib import Path

import numpy as np
import pytest

from voxel_addon.core.errors import VoxelError
from voxel_addon.formats import anvil, budget, lz4, minecraft, nbt, region, vox
from voxel_addon.formats.region import Region, RegionError
from voxel_addon.world import World

from . import hostile as H
from . import mcfiles as mc
from . import voxfiles as vf
from ..memory import peak_of

MIB = 1 << 20
ROOT = Path(__file__).resolve().parents[2]




# ---- through the CLI ----------------------------------------------------------------
def _save(tmp, mca: bytes, level: bytes | None = None) -> Path:
    save = tmp / "save"
    (save / "region").mkdir(parents=True)
    (save / "region" / "r.0.0.mca").write_bytes(mca)
    if level is not None:
        (save / "level.dat").write_bytes(level)
    return save


def _vox(tmp, data: bytes) -> Path:
    (tmp / "m.vox").write_bytes(data)
    return tmp / "m.vox"


# name -> (writer of the source in a folder, the refusal's words, refused before the
# world file is opened)
CASES = {
    "aliased zlib bomb": (lambda t: _save(t, H.aliased(H.zlib_bomb(64 * MIB), 2)),
                          "share sector 2", True),
    "aliased slow LZ4 block": (lambda t: _save(t, H.aliased(H.slow_lz4(), 4)),
                               "share sector 2", True),
    "aliased 32 MiB NBT": (lambda t: _save(t, H.aliased(zlib.compress(H.big_nbt(), 9), 2)),
                           "share sector 2", True),
    "30M tiny tags kept": (lambda t: _save(t, H.one_chunk(H.tag_bomb())),
                           "more than 524,288 NBT tags in one chunk", False),
    "30M tiny tags skipped": (lambda t: _save(t, H.one_chunk(H.tag_bomb(key="x"))),
                              "more than 524,288 NBT tags in one chunk", False),
    "NBT 100k levels deep": (lambda t: _save(t, H.one_chunk(H.deep_chunk(100_000))),
                             "deeper than 512", False),
    "level.dat of 60M tags": (lambda t: _save(t, H.one_chunk(H.good_chunk()), H.level_bomb()),
                              "inflates past 16 MiB", True),
    "level.dat of 15M tags": (lambda t: _save(t, H.one_chunk(H.good_chunk()),
                                              H.level_bomb(15_000_000)),
                              "more than 262,144 NBT tags", True),
    "vox group of 130k children": (lambda t: _vox(t, H.wide_group()), "130000 children", True),
    "vox group of 60k same children": (lambda t: _vox(t, H.wide_group(60_000)),
                                       "reaches node 2 twice", True),
    "vox binary tree of one node": (lambda t: _vox(t, H.binary_tree()), "twice", True),
    "vox cycle": (lambda t: _vox(t, H.cycle()), "reaches node 1 twice", True),
    "vox 30k instances": (lambda t: _vox(t, H.instances()), "1,048,576 voxels", True),
    "vox 4k instances of 4096": (lambda t: _vox(t, H.instances(4096, 16)), "1,048,576 voxels",
                                 True),
}


def _cap():
    # a broken limit must fail the test, not take the machine: 2 GiB of address space
    resource.setrlimit(resource.RLIMIT_AS, (2 << 30, 2 << 30))


# Linux keeps the high-water mark of a process's old image across exec, so the child
# of a fork from this test process (hundreds of MB after the suite's earlier tests)
# would report that as its own peak: a small Python in between forks the real CLI, so
# the inherited mark is the wrapper's few MB.
_WRAP = ("import os, sys\n"
         "pid = os.fork()\n"
         "if pid == 0:\n"
         "    os.execv(sys.executable, [sys.executable, *sys.argv[2:]])\n"
         "_, status, usage = os.wait4(pid, 0)\n"
         "open(sys.argv[1], 'w').write(f'{os.waitstatus_to_exitcode(status)} {usage.ru_maxrss}')\n")


def cli(world: Path, src: Path):
    """(exit code, stdout, stderr, peak RSS in bytes, seconds) of the real CLI, killed
    after 60 s."""
    env = dict(os.environ, PYTHONPATH=str(ROOT), OPENBLAS_NUM_THREADS="1")
    out, err, res = (src.parent / n for n in ("out.txt", "err.txt", "rusage.txt"))
    res.unlink(missing_ok=True)
    t0 = time.perf_counter()
    with open(out, "wb") as o, open(err, "wb") as e:
        p = subprocess.Popen([sys.executable, "-c", _WRAP, str(res), "-m", "voxel_addon",
                              "import", "--world", str(world), "--from", str(src)],
                             stdout=o, stderr=e, env=env, preexec_fn=_cap,
                             start_new_session=True)
        timer = threading.Timer(60, os.killpg, (p.pid, signal.SIGKILL))
        timer.start()
        try:
            p.wait()
        finally:
            timer.cancel()
    dt = time.perf_counter() - t0
    code, rss = map(int, res.read_text().split()) if res.exists() else (p.returncode, 0)
    rss *= 1 if sys.platform == "darwin" else 1024
    return code, out.read_text(), err.read_text(), rss, dt


@pytest.fixture(scope="module")
def world_bytes(tmp_path_factory):
    w = tmp_path_factory.mktemp("w") / "w.sqlite"
    with World.create(w, seed=0, generator="empty", loader=False) as world:
        world.set_block(1, 2, 3, "stone")
    return w.read_bytes()


@pytest.mark.parametrize("case", list(CASES))
def test_cli_refuses_with_one_line(tmp_path, world_bytes, case):
    write, words, early = CASES[case]
    src = write(tmp_path)
    new, old = tmp_path / "new.sqlite", tmp_path / "old.sqlite"
    old.write_bytes(world_bytes)
    # early: refused before a world file is opened (into a missing folder, which the
    # world's opening would name instead); else after, a new file removed again
    # (cli/importer.py) and an old one as it was
    for w in ([tmp_path / "missing" / "w.sqlite"] if early else [new, old]):
        rc, out, err, rss, dt = cli(w, src)
        assert rc == 2, (case, rc, out, err[-2000:])
        assert err.startswith("error: ") and err.count("\n") == 1, err[-2000:]
        assert words in err, err
        assert rss < 600 * MIB, (case, rss >> 20)
        assert dt < 10, (case, dt)
    assert sorted(p.name for p in tmp_path.glob("*.sqlite*")) == ["old.sqlite"]
    assert hashlib.sha256(old.read_bytes()).digest() == hashlib.sha256(world_bytes).digest()


# ---- the decoders' limits -----------------------------------------------------------
@pytest.fixture(scope="module")
def zbomb():
    return H.zlib_bomb(64 * MIB)


@pytest.mark.parametrize("kind", [1, 2])
def test_region_inflates_at_most_its_limit(kind, zbomb):
    body = H.zlib_bomb(64 * MIB, 31) if kind == 1 else zbomb
    with pytest.raises(ValueError, match="larger"):
        region.decompress(kind, body, MIB)
    assert peak_of(lambda: pytest.raises(ValueError, region.decompress, kind, body, MIB)) \
        < 4 * MIB
    # a chunk: at most MAX_NBT (32 MiB) inflated, reported damaged
    reg = Region("r.0.0.mca", H.single(body, kind))
    assert peak_of(lambda: pytest.raises(RegionError, reg.payload, 0, 0)) < 80 * MIB


def test_lz4_decodes_at_most_its_limit():
    bomb = H.lz4_bomb(16, 16 * MIB)          # 256 MiB of zeros in 1 MB
    assert lz4.decode_stream(H.lz4_bomb(2, MIB), 2 * MIB) == bytes(2 * MIB)
    with pytest.raises(ValueError, match="larger"):
        lz4.decode_stream(bomb, MIB)
    assert peak_of(lambda: pytest.raises(ValueError, lz4.decode_stream, bomb, MIB)) < 4 * MIB
    assert peak_of(lambda: pytest.raises(ValueError, region.decompress, 4, bomb)) < 120 * MIB


def test_region_budget_stops_decoding():
    data = mc.region({(0, 0): H.big_nbt(4 * MIB), (1, 0): H.big_nbt(4 * MIB)}, 2)
    reg = Region("r.0.0.mca", data)
    b = budget.Budget(6 * MIB, 1 << 30)
    assert len(reg.payload(0, 0, b)) == 4 * MIB and b.bytes == 2 * MIB
    with pytest.raises(budget.Exceeded, match="MiB decompressed"):
        reg.payload(1, 0, b)
    assert peak_of(lambda: pytest.raises(budget.Exceeded, reg.payload, 1, 0,
                                         budget.Budget(MIB, 1))) < 3 * MIB


def test_import_budget_refuses_the_import(tmp_path, monkeypatch):
    secs = {0: np.full((16, 16, 16), "minecraft:stone", object)}
    mc.write_region(tmp_path / "region", {(x, 0): mc.chunk_nbt(x, 0, secs) for x in range(4)})
    monkeypatch.setattr(budget, "TAGS_FLOOR", 50)
    monkeypatch.setattr(budget, "TAGS_PER_INPUT", 0)
    with World.create(tmp_path / "w.sqlite", seed=0, generator="empty", loader=False) as w:
        with pytest.raises(VoxelError, match="more than 50 NBT tags in this import"):
            minecraft.import_world(w, tmp_path)
        assert w.file.chunk_count() == 0
    monkeypatch.setattr(budget, "TAGS_FLOOR", 1 << 24)
    monkeypatch.setattr(budget, "BYTES_FLOOR", 3 * len(mc.chunk_nbt(0, 0, secs)) // 2)
    monkeypatch.setattr(budget, "BYTES_PER_INPUT", 0)
    with World.create(tmp_path / "v.sqlite", seed=0, generator="empty", loader=False) as w:
        with pytest.raises(VoxelError, match="decompressed in this import"):
            minecraft.import_world(w, tmp_path)


def test_region_sectors_belong_to_one_chunk(tmp_path):
    good = mc.region({(0, 0): H.good_chunk(), (1, 0): H.good_chunk()}, 2)
    assert sorted(Region("r.0.0.mca", good).chunks()) == [(0, 0), (1, 0)]
    head = bytearray(good)

    def entry(i, off, count):
        b = bytearray(head)
        b[4 * i:4 * i + 4] = (off << 8 | count).to_bytes(4, "big")
        return bytes(b)
    n = len(good) // 4096
    assert good[:8] == bytes([0, 0, 2, 1, 0, 0, 3, 1])   # chunk 0: sector 2, chunk 1: 3
    cases = {"share sector": entry(0, 2, 2),            # chunk 0 runs into chunk 1
             "share sector ": entry(5, 2, 1),           # another entry, same start
             "into the region header": entry(7, 1, 1),
             "past the end": entry(7, n, 2)}
    for msg, data in cases.items():
        with pytest.raises(RegionError, match=msg.strip()):
            Region("r.0.0.mca", data)
        f = tmp_path / "r.0.0.mca"
        f.write_bytes(data)
        with pytest.raises(VoxelError, match=msg.strip()):
            minecraft.regions_of(f)
    with pytest.raises(RegionError, match="share sector"):
        Region("r.0.0.mca", H.aliased(zlib.compress(H.good_chunk()), 2))


def test_a_region_outside_the_world_is_refused_by_its_name(tmp_path):
    """r.X.Z.mca names where its chunks go: past the world's reach (2^30 blocks) the
    positions wrap in generation or overflow SQLite's integers."""
    good = mc.region({(0, 0): H.good_chunk()}, 2)
    assert Region("r.-2097152.2097151.mca", good).chunks()   # the edge itself is inside
    for name in ("r.2097152.0.mca", "r.0.-2097153.mca", f"r.{1 << 60}.0.mca"):
        (tmp_path / "region").mkdir(exist_ok=True)
        f = tmp_path / "region" / name
        f.write_bytes(good)
        with pytest.raises(VoxelError, match="outside the world"):
            minecraft.regions_of(tmp_path)
        f.unlink()

def test_nbt_lengths_are_checked_before_allocating():
    head = H.chunk_head()
    for tag, item in ((7, b""), (11, b""), (12, b""), (9, b"\x04"), (9, b"\x0a"), (9, b"\x08")):
        doc = head + H.named(tag, "x") + item + (0x7FFFFFFF).to_bytes(4, "big") + b"\x00"
        with pytest.raises(nbt.NbtError, match="ends early"):
            nbt.parse(doc)
        assert peak_of(lambda: pytest.raises(nbt.NbtError, nbt.parse, doc)) < MIB
    neg = head + H.named(12, "x") + (-5).to_bytes(4, "big", signed=True) + b"\x00"
    with pytest.raises(nbt.NbtError, match="negative"):
        nbt.parse(neg)


def test_nbt_depth_is_iterative_and_bounded():
    assert "Heightmaps" in nbt.parse(H.deep_chunk(500))   # main: RecursionError
    assert "Heightmaps" in nbt.parse(H.deep_chunk(510))
    for d in (512, 100_000):
        for keep in (None, anvil.KEEP):                   # built and skipped
            with pytest.raises(nbt.Hostile, match="deeper than 512"):
                nbt.parse(H.deep_chunk(d), keep)
    # a list of lists nests too
    doc = H.chunk_head() + H.named(9, "x") + (b"\x09" + (1).to_bytes(4, "big")) * 600 \
        + b"\x00" + (0).to_bytes(4, "big") + b"\x00"
    with pytest.raises(nbt.Hostile, match="deeper"):
        nbt.parse(doc)


@pytest.mark.parametrize("key", ["sections", "x"])      # built, and skipped unbuilt
def test_nbt_tag_count_is_bounded(key):
    bomb = H.tag_bomb(anvil.CHUNK_TAGS, key)   # and the other tags of the chunk
    with pytest.raises(nbt.TooMany, match="in one chunk"):
        anvil.read(bomb)
    # the budget applies before the tags are built: ~1M empty dicts at most
    assert peak_of(lambda: pytest.raises(nbt.TooMany, nbt.parse, bomb, anvil.KEEP, 20_000)) \
        < 8 * MIB
    root, tags = nbt.read(mc.chunk_nbt(0, 0, {0: np.full((16, 16, 16), "minecraft:stone",
                                                         object)}))
    assert 10 < tags < 100 and root["DataVersion"] == 3953


def test_real_shaped_chunks_are_far_below_the_tag_limit():
    rng = np.random.default_rng(0)
    names = np.array([f"minecraft:block_{i}" for i in range(40)] + ["minecraft:oak_stairs"],
                     object)
    secs = {y: names[rng.integers(0, len(names), (16, 16, 16))] for y in range(-4, 20)}
    _, tags = nbt.read(mc.chunk_nbt(0, 0, secs))
    assert tags < 4000 < anvil.CHUNK_TAGS // 100
    assert len(anvil.read(mc.chunk_nbt(0, 0, secs)).sections) == 24


def test_level_dat_is_read_for_its_version_only(tmp_path):
    (tmp_path / "level.dat").write_bytes(H.level_bomb(3_000_000))
    with pytest.raises(VoxelError, match="NBT tags"):
        minecraft.level_version(tmp_path)
    (tmp_path / "level.dat").write_bytes(H.level_bomb(minecraft.LEVEL_BYTES))
    with pytest.raises(VoxelError, match="inflates past 16 MiB"):
        minecraft.level_version(tmp_path)
    mc.level_dat(tmp_path, 4000)
    assert minecraft.level_version(tmp_path) == 4000
    (tmp_path / "level.dat").write_bytes(b"\x1f\x8b damaged")
    assert minecraft.level_version(tmp_path) is None


@pytest.mark.parametrize("make,msg", [
    (lambda: H.wide_group(), "130000 children"),
    (lambda: H.wide_group(60_000), "reaches node 2 twice"),
    (lambda: H.binary_tree(), "twice"),
    (lambda: H.cycle(), "reaches node 1 twice"),
    (lambda: H.instances(1100), "more than 1,048,576 voxels"),
    (lambda: H.shapes(vox.MAX_INSTANCES + 1), "more than 32,768 models"),
    (lambda: vf.file(vf.model((2, 2, 2), [(1, 1, 1, 5)] * 9)), "9 voxels in a model of 2x2x2"),
    (lambda: vf.file(b"".join([H.cube_model(128)] * 3)), "models hold more than 4,194,304"),
])
def test_vox_scene_graph_budgets(make, msg):
    data = make()
    with pytest.raises(vox.VoxError, match=msg):
        vox.read(data)
    if len(data) < (1 << 20):  # tracemalloc is slow on the 65k nodes of the last one
        assert peak_of(lambda: pytest.raises(vox.VoxError, vox.read, data)) < 40 * MIB


def test_vox_budget_leaves_real_scenes():
    s = vox.read(H.instances(256, 16))                 # 1,048,576 placed voxels
    assert len(s.instances) == 256
    xyz, _, size = vox.voxels(s)
    assert len(xyz) == 256 * 4096 and size.tolist() == [1600, 48, 16]


def test_region_files_are_read_a_chunk_at_a_time(tmp_path):
    f = tmp_path / "r.0.0.mca"
    f.write_bytes(mc.region({(0, 0): H.good_chunk(), (1, 0): H.good_chunk()}, 2))
    with open(f, "r+b") as h:      # 256 MiB of (sparse) sectors no chunk points at
        h.truncate(256 * MIB)

    def go():
        reg = Region(f)
        assert reg.stored == 2 * 4096
        assert [len(anvil.read(reg.payload(cx, cz)).sections) for cx, cz in reg.chunks()] == [1, 1]
    assert peak_of(go) < 8 * MIB


def test_the_pure_python_lz4_decoder_equals_the_package():
    """Without the `lz4` package (a Blender without the wheel) the pure-Python block
    decoder runs: the package is its oracle, on blocks of runs, noise and text."""
    from lz4 import block
    rng = np.random.default_rng(4)
    for n in (0, 1, 15, 16, 300, 70_000):
        for raw in (bytes(n), rng.integers(0, 256, n, np.uint8).tobytes(),
                    (b"minecraft:stone " * (n // 16 + 1))[:n],
                    rng.integers(0, 3, n, np.uint8).tobytes()):
            src = block.compress(raw, store_size=False)
            assert lz4._decode(src, len(raw)) == raw
            assert lz4.decode_block(src, len(raw)) == raw
            if raw:
                with pytest.raises(ValueError):
                    lz4._decode(src, len(raw) - 1)
