"""The block table's targets all exist, unknown names never become air, and the
import/export commands' user mistakes are one line with exit code 2, the world
file untouched."""
from __future__ import annotations

import hashlib

import pytest

from voxel_addon.cli import main
from voxel_addon.core.blocks import REGISTRY
from voxel_addon.formats import mapping

from . import voxfiles as vf


def test_every_target_is_a_block_and_unknown_is_never_air():
    names = set(REGISTRY.names())
    for name in list(mapping.EXACT) + [f"red{sub}" for sub, _ in mapping.CLASSES]:
        block, rgb, how = mapping.lookup("minecraft:" + name)
        assert block in names, name
        assert (rgb is None) == (block != "color"), name
    for name in ("minecraft:air", "minecraft:cave_air", "minecraft:barrier"):
        assert mapping.lookup(name)[0] == "air"
    for name in ("minecraft:something_new", "mod:widget", "minecraft:"):
        assert mapping.lookup(name)[:3:2] == ("stone", "fallback")
    assert mapping.lookup("minecraft:light_blue_wool")[1] == mapping.DYES["light_blue"]
    assert mapping.lookup("minecraft:blue_wool")[1] == mapping.DYES["blue"]
    assert mapping.lookup("minecraft:oak_stairs")[0] == "planks"
    assert mapping.lookup("minecraft:wall_torch")[0] == "torch"


def _digest(p):
    return hashlib.sha256(p.read_bytes()).hexdigest()


def test_cli_mistakes_are_one_line(tmp_path, capsys):
    w = tmp_path / "w.sqlite"
    src = tmp_path / "m.vox"
    src.write_bytes(vf.file(vf.model((2, 2, 2), [(0, 0, 0, 1)])))
    assert main(["import", "--world", str(w), "--from", str(src)]) == 0
    before = _digest(w)
    bad = [
        ["import", "--world", str(w), "--from", str(tmp_path / "nope")],
        ["import", "--world", str(w), "--from", str(src), "--at", "0", "0", "256"],
        ["import", "--world", str(w), "--from", str(src), "--area", "0", "0", "1", "1"],
        ["import", "--world", str(w), "--from", str(tmp_path)],               # no regions
        ["import", "--world", str(tmp_path / "x" / "w.sqlite"), "--from", str(src)],
        ["export", "--world", str(w), "--box", "0", "0", "0", "0", "5", "5", "--out",
         str(tmp_path / "o.vox")],
        ["export", "--world", str(w), "--box", "0", "0", "0", "5", "5", "300", "--out",
         str(tmp_path / "o.vox")],
        ["export", "--world", str(w), "--box", "0", "0", "0", "5", "5", "5", "--out",
         str(tmp_path / "o.txt")],
    ]
    (tmp_path / "broken.vox").write_bytes(b"VOX \x96\x00\x00\x00MAIN\xff\xff\xff\x7f")
    bad.append(["import", "--world", str(w), "--from", str(tmp_path / "broken.vox")])
    for argv in bad:
        capsys.readouterr()
        assert main(argv) == 2, argv
        err = capsys.readouterr().err.strip()
        assert err.startswith("error: ") and "\n" not in err, (argv, err)
    assert _digest(w) == before
    assert not (tmp_path / "x").exists() and not (tmp_path / "o.vox").exists()
