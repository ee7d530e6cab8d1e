"""What an import checks before its first write (issue 26): a damaged chunk (a
malformed DataVersion among good ones) is skipped and counted, never the end of the
import; a world from before 1.13 (its level.dat, or every chunk) is refused with
nothing written and no file left behind; a .vox whose voxels cannot be written
leaves no palette colour behind."""
from __future__ import annotations

import resource
import sqlite3
import subprocess
import sys

import numpy as np
import pytest

from voxel_addon.cli import main
from voxel_addon.core import colors
from voxel_addon.formats import minecraft
from voxel_addon.world import World

from . import mcfiles as mc
from . import voxfiles as vf

STONE = {0: np.full((16, 16, 16), "minecraft:stone", object)}


def _files(p):
    return sorted(x.name for x in p.parent.glob(p.name + "*"))


def test_damaged_chunk_is_skipped_and_counted(tmp_path, capsys):
    body = mc.chunk_nbt(0, 0, STONE)
    chunks = {(x, z): body for x in range(8) for z in range(5)}  # 40: more than a batch
    bad = mc.nbt({"DataVersion": "3953", "xPos": 1, "zPos": 4, "sections": mc.T("list", [], "compound")})  # a string
    chunks[(1, 4)] = bad  # read after the first batch of 32 is written
    mc.write_region(tmp_path / "save" / "region", chunks, 2)
    w = tmp_path / "w.sqlite"
    assert main(["import", "--world", str(w), "--from", str(tmp_path / "save")]) == 0
    out = capsys.readouterr().out
    assert "39 chunks imported" in out and "skipped, damaged: 1" in out
    assert "r.0.0.mca chunk (1, 4): no DataVersion" in out
    with World.open(w, readonly=True, loader=False) as world:
        assert world.file.chunk_count() == 39
        assert not world.file.has_chunk(minecraft.to_key(1, 4))


@pytest.mark.parametrize("how", ["level.dat", "chunks"])
def test_world_before_1_13_is_refused_before_any_write(tmp_path, capsys, how):
    save = tmp_path / "save"
    old = mc.nbt({"DataVersion": 1343, "Level": {"xPos": 0, "zPos": 0,
                                                 "Blocks": mc.T("bytes", [1] * 10)}})
    if how == "level.dat":  # its chunks would read as 1.13+: level.dat decides first
        mc.write_region(save / "region", {(x, 0): mc.chunk_nbt(x, 0, STONE) for x in range(40)})
        mc.level_dat(save, 1343)
    else:
        mc.write_region(save / "region", {(x, 0): old for x in range(40)})
    w = tmp_path / "w.sqlite"
    assert main(["import", "--world", str(w), "--from", str(save)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "1.13" in err[0], err
    assert _files(w) == []  # the file this import created is gone with its -wal, -shm
    # into an existing world: the file is kept, nothing in it changed
    with World.create(w, seed=0, generator="empty", loader=False):
        pass
    before = w.read_bytes()
    assert main(["import", "--world", str(w), "--from", str(save)]) == 2
    assert w.exists() and w.read_bytes() == before


def _vox_into(world_path, vox_path, limit):
    """The CLI importing a .vox under a file-size limit (a child process: the
    limit is its own); the limit makes the write fail as a full disk does."""
    def lower():
        resource.setrlimit(resource.RLIMIT_FSIZE, (limit, resource.RLIM_INFINITY))
    return subprocess.run([sys.executable, "-m", "voxel_addon", "import", "--world",
                           str(world_path), "--from", str(vox_path)],
                          capture_output=True, text=True, preexec_fn=lower, timeout=120)


def test_vox_palette_only_with_its_voxels(tmp_path):
    """The palette colours go into the file in the voxels' transaction: with room
    in the journal for the palette row but not for the voxels, neither lands."""
    w = tmp_path / "w.sqlite"
    with World.create(w, seed=0, generator="empty", loader=False):
        pass
    rng = np.random.default_rng(5)
    xyz = rng.integers(0, 40, (3000, 3))
    xyz = np.unique(xyz, axis=0)
    vs = [(x, y, z, int(rng.integers(1, 200))) for x, y, z in xyz.tolist()]
    src = tmp_path / "m.vox"
    src.write_bytes(vf.file(vf.model((40, 40, 40), vs) + vf.rgba(rng.integers(0, 256, (255, 3)))))
    r = _vox_into(w, src, 40 << 10)  # the -shm (32 KiB) and the palette row fit, not the voxels
    assert r.returncode == 2, r.stderr
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and "nothing of this import was written" in lines[0], lines
    db = sqlite3.connect(w)
    assert db.execute("SELECT value FROM meta WHERE key=?", (colors.KEY,)).fetchone() is None
    assert db.execute("SELECT COUNT(*) FROM edits").fetchone()[0] == 0
    db.close()
    r = _vox_into(w, src, resource.RLIM_INFINITY)  # room again: both land
    assert r.returncode == 0, r.stderr
    with World.open(w, readonly=True, loader=False) as world:
        assert colors.KEY in world.file.meta and world.file.edit_count() == int(len(vs))
