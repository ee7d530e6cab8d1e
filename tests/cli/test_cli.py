"""The command line as a user runs it: real subprocesses, real files."""
from __future__ import annotations

import hashlib
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from voxel_addon.core.blocks import REGISTRY

ROOT = Path(__file__).resolve().parents[2]


def cli(*args, cwd=None):
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    return subprocess.run([sys.executable, "-m", "voxel_addon", *map(str, args)],
                          capture_output=True, text=True, env=env, cwd=cwd, timeout=600)


def digest(p: Path) -> str:
    return hashlib.sha256(p.read_bytes()).hexdigest()


@pytest.fixture(scope="module")
def flat_world(tmp_path_factory):
    p = tmp_path_factory.mktemp("cli") / "flat.sqlite"
    r = cli("generate", "--world", p, "--seed", 42, "--generator", "flat", "--center", 40, -5, "--radius", 1)
    assert r.returncode == 0, r.stderr
    return p


def test_generate_info_and_extend(flat_world):
    info = json.loads(cli("info", "--world", flat_world).stdout)
    assert info["seed"] == 42 and info["generator"] == "flat" and info["chunks"] == 9
    assert info["format_version"] == 1
    names = {b["name"]: b for b in info["block_types"]}
    for n in ("air stone dirt grass snow sand ore log leaves flowers tall_grass wheat mushroom "
              "glowing_mushroom cactus glass water lamp_red lamp_green lamp_blue").split():
        assert n in names
    assert set(names["water"]) == {"id", "name", "shape", "render", "light_opaque", "emission", "attenuation"}
    assert names["water"]["render"] == "blend" and names["water"]["attenuation"] > 0
    assert names["lamp_red"]["emission"] == [15, 0, 0]
    # --center is in blocks: (40, -5) is chunk (2, -1); radius 1 -> chunks 1..3 x -2..0
    r = cli("generate", "--world", flat_world, "--center", 48, -16, "--radius", 1)
    assert r.returncode == 0, r.stderr
    assert json.loads(cli("info", "--world", flat_world).stdout)["chunks"] == 12


def test_edit_and_dump(flat_world, tmp_path):
    assert cli("edit", "--world", flat_world, "--set", 33, -10, 100, "lamp_blue").returncode == 0
    assert cli("edit", "--world", flat_world, "--clear", 33, -10, 63).returncode == 0
    out = tmp_path / "c.npz"
    r = cli("dump", "--world", flat_world, "--chunk", 2, -1, "--out", out)
    assert r.returncode == 0, r.stderr
    z = np.load(out)
    assert z["blocks"].shape == (16, 16, 256) and z["blocks"].dtype == np.uint16
    assert z["blocks3x3"].shape == (48, 48, 256) and z["light"].shape == (16, 16, 256)
    assert z["light"].dtype == np.uint16
    assert z["blocks"][1, 6, 100] == REGISTRY.id("lamp_blue")   # (33, -10) is local (1, 6)
    assert z["blocks"][1, 6, 63] == 0 and z["blocks"][1, 6, 62] == REGISTRY.id("dirt")
    assert np.array_equal(z["blocks3x3"][16:32, 16:32], z["blocks"])


def test_dump_generates_missing_neighbours_without_saving(flat_world, tmp_path):
    before = digest(flat_world)
    r = cli("dump", "--world", flat_world, "--chunk", 10, 10, "--out", tmp_path / "far.npz")
    assert r.returncode == 0, r.stderr
    assert (np.load(tmp_path / "far.npz")["blocks3x3"][:, :, 0] == REGISTRY.id("stone")).all()
    assert digest(flat_world) == before


@pytest.mark.parametrize("args, message", [
    (("edit", "--set", 1, 1, 1, "unobtainium"), "unknown block name 'unobtainium'"),
    (("edit", "--set", 1, 1, 300, "stone"), "outside the world"),
    (("edit", "--clear", 1, 1, -1), "outside the world"),
    (("edit", "--set", "a", 1, 1, "stone"), "whole numbers"),
    (("edit", "--clear", 1, "b", 1), "invalid int value"),
    (("generate", "--seed", 7), "keeps its seed"),
    (("generate", "--generator", "overworld"), "uses generator"),
    (("generate", "--radius", -1), "--radius"),
    (("dump", "--chunk", 0, "x", "--out", "o.npz"), "invalid int value"),
    (("dump", "--chunk", 1 << 62, 0, "--out", "o.npz"), "outside the world"),
    (("generate", "--center", 0, 1 << 64), "outside the world"),
    (("edit", "--set", -(1 << 63), 1, 100, "stone"), "outside the world"),
])
def test_bad_input_is_one_line_and_changes_nothing(flat_world, args, message, tmp_path):
    before = digest(flat_world)
    r = cli(args[0], "--world", flat_world, *args[1:], cwd=tmp_path)
    assert r.returncode == 2
    assert message in r.stderr and len(r.stderr.strip().splitlines()) == 1, r.stderr
    assert "Traceback" not in r.stderr
    assert digest(flat_world) == before


@pytest.mark.parametrize("content", [None, b"", b"this is not sqlite at all" * 100])
def test_missing_or_unreadable_file(tmp_path, content):
    p = tmp_path / "w.sqlite"
    if content is not None:
        p.write_bytes(content)
    for args in (("info",), ("edit", "--set", 0, 0, 0, "stone"), ("dump", "--chunk", 0, 0, "--out", tmp_path / "o.npz")):
        r = cli(args[0], "--world", p, *args[1:])
        assert r.returncode == 2 and len(r.stderr.strip().splitlines()) == 1, r.stderr
        assert ("no world file" if content is None else "not a readable world file") in r.stderr
    assert (p.read_bytes() == content) if content is not None else not p.exists()
    r = cli("generate", "--world", tmp_path / "new.sqlite", "--radius", 0)
    assert r.returncode == 2 and "--seed is needed" in r.stderr


@pytest.mark.parametrize("kind, words", [
    ("folder", "is a folder"), ("fifo", "is a pipe"), ("dangling", "symbolic link to nothing"),
    ("loop", "symbolic link to nothing")])
def test_a_world_path_that_holds_no_file_says_what_is_there(tmp_path, kind, words, capsys):
    # a pipe or a dangling link was 'no world file' (generate --seed: it cannot be
    # made there either), a folder 'does not exist' for map and bake
    from voxel_addon.cli import main
    from voxel_addon.formats import vox
    p = tmp_path / "w.sqlite"
    {"folder": p.mkdir, "fifo": lambda: os.mkfifo(p),
     "dangling": lambda: p.symlink_to(tmp_path / "gone" / "w.sqlite"),
     "loop": lambda: p.symlink_to(p)}[kind]()
    (tmp_path / "x.vox").write_bytes(vox.write(np.ones((2, 2, 2), np.uint8), vox.default_palette()))
    for args in (("generate", "--seed", 1, "--radius", 0), ("info",),
                 ("map", "--out", tmp_path / "m.png"), ("far", "--center", 0, 0, "--far", 1),
                 ("bake", "--region", 0, 0, 4, 4, "--out", tmp_path / "b.glb"),
                 ("import", "--from", tmp_path / "x.vox")):
        assert main([args[0], "--world", str(p), *map(str, args[1:])]) == 2
        err = capsys.readouterr().err
        assert words in err and len(err.strip().splitlines()) == 1, (args, err)
    assert os.path.lexists(p) and not (tmp_path / "gone").exists()


def test_newer_world_is_refused(tmp_path):
    import sqlite3
    p = tmp_path / "w.sqlite"
    assert cli("generate", "--world", p, "--seed", 1, "--generator", "flat", "--radius", 0).returncode == 0
    db = sqlite3.connect(p)
    db.execute("UPDATE meta SET value='2' WHERE key='format_version'")
    db.commit()
    db.close()
    before = digest(p)
    r = cli("edit", "--world", p, "--set", 0, 0, 100, "stone")
    assert r.returncode == 2 and "newer" in r.stderr
    assert digest(p) == before


@pytest.mark.parametrize("key, value, message", [
    ("seed", "abc", "seed 'abc' is no whole number"), ("seed", None, "no seed"),
    ("generator", None, "no generator"), ("generator_version", "x", "'x' is not a number")])
def test_damaged_meta_rows_are_one_line_in_info_too(tmp_path, key, value, message):
    import sqlite3
    from voxel_addon.world import World
    p = tmp_path / "w.sqlite"
    World.create(p, seed=1, generator="flat", loader=False).close()
    db = sqlite3.connect(p)
    db.execute("DELETE FROM meta WHERE key=?", (key,))
    if value is not None:
        db.execute("INSERT INTO meta VALUES (?, ?)", (key, value))
    db.commit()
    db.close()
    before = digest(p)
    r = cli("info", "--world", p)  # (it printed a KeyError's or ValueError's traceback)
    assert r.returncode == 2 and message in r.stderr, r.stderr[-2000:]
    assert len(r.stderr.strip().splitlines()) == 1 and digest(p) == before


def test_a_command_builds_its_own_parser_only():
    """`import ...` does not import what other commands' options list (meshing,
    render); the whole parser still lists every command."""
    code = ("import sys, voxel_addon.cli as c; c.parser(c._module(['import', '-h'])); "
            "print(sorted(m for m in sys.modules if m.startswith('voxel_addon.')))")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                       env=dict(os.environ, PYTHONPATH=str(ROOT)))
    assert r.returncode == 0, r.stderr
    assert "voxel_addon.meshing" not in r.stdout and "voxel_addon.cli.importer" in r.stdout
    whole = cli("--help").stdout
    assert all(c in whole for c in ("generate", "import", "export", "render", "bench"))
    assert "--from" in cli("import", "--help").stdout


def test_a_minecraft_import_loads_no_meshing_nor_resource_packs(tmp_path):
    """The whole `import` of a save (its start is ~a third of a 1,000-chunk import's
    CPU): no meshing, OpenCL, streaming or resource pack modules, nor uuid's platform."""
    from tests.formats import mcfiles as mc
    mc.write_region(tmp_path / "save" / "region",
                    {(0, 0): mc.chunk_nbt(0, 0, {0: np.full((16, 16, 16), "minecraft:stone", object)})})
    code = ("import runpy, sys\nsys.argv = ['voxel_addon', 'import', '--world', sys.argv[1], "
            "'--from', sys.argv[2]]\ntry:\n    runpy.run_module('voxel_addon', run_name='__main__')\n"
            "except SystemExit as e:\n    assert not e.code, e.code\n"
            "print(sorted(m for m in sys.modules if m.startswith('voxel_addon.') or m == 'uuid'))")
    r = subprocess.run([sys.executable, "-c", code, str(tmp_path / "w.sqlite"), str(tmp_path / "save")],
                       capture_output=True, text=True, env=dict(os.environ, PYTHONPATH=str(ROOT)))
    assert r.returncode == 0, r.stderr
    mods = r.stdout.splitlines()[-1]
    assert "1 chunks imported" in r.stdout and "voxel_addon.formats.minecraft" in mods
    for m in ("voxel_addon.meshing", "voxel_addon.opencl", "voxel_addon.world.stream",
              "voxel_addon.world.payload", "voxel_addon.mcres.pack", "'uuid'"):
        assert m not in mods, m


def test_ctrl_c_in_generate_says_what_it_kept(tmp_path):
    # it said only 'interrupted': whether anything was written, and that the same
    # command finishes it, was the user's guess
    import signal
    import sqlite3
    import time
    p = tmp_path / "w.sqlite"
    assert cli("generate", "--world", p, "--seed", 1, "--radius", 0, "--backend", "numpy").returncode == 0
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    proc = subprocess.Popen([sys.executable, "-m", "voxel_addon", "generate", "--world", str(p),
                             "--radius", "30", "--backend", "numpy"],
                            stderr=subprocess.PIPE, text=True, env=env)
    db = sqlite3.connect(p)
    try:
        end = time.monotonic() + 60
        while db.execute("SELECT COUNT(*) FROM chunks").fetchone()[0] < 40 and time.monotonic() < end:
            time.sleep(0.02)
        proc.send_signal(signal.SIGINT)
        err = proc.communicate(timeout=60)[1]
        stored = db.execute("SELECT COUNT(*) FROM chunks").fetchone()[0] - 1
    finally:
        proc.kill()
        db.close()
    assert proc.returncode == 130 and "Traceback" not in err, err[-2000:]
    kept = [ln for ln in err.replace("\r", "\n").splitlines() if "were written and kept" in ln]
    assert len(kept) == 1 and "the same command again generates the rest" in kept[0], err
    said = int(kept[0].split()[0])  # a batch stored as the signal came may be left uncounted
    assert 32 <= said <= stored <= said + 32 and stored < 61 * 61 - 1, (said, stored)
    r = cli("generate", "--world", p, "--radius", 2, "--backend", "numpy")
    assert r.returncode == 0 and "already present" in r.stderr
