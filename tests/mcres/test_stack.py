"""The resource stack: packs over the jar (the last one wins, a jar always at the
bottom), zips, folders and a zip with its folder around the pack, the launcher
folders of each platform, and bad packs refused in one line."""
from __future__ import annotations

import os
import zipfile

import pytest

from voxel_addon.core.errors import VoxelError
from voxel_addon.mcres import Resources, Stack, discover
from voxel_addon.mcres.stack import launcher_dirs

from . import packfiles as pf

STONE = "assets/minecraft/textures/block/stone.png"


def over(tmp_path, name, colour, zipped):
    """A pack that only repaints stone."""
    p = tmp_path / name
    if not zipped:
        p.mkdir()
    content = {STONE: pf.png_bytes(pf.solid(colour)), "pack.mcmeta": b"{}"}
    return pf.write(p, content, zipped=zipped)


def stone(stack):
    return tuple(Resources(stack).texture("minecraft:block/stone").rgba[8, 8, :3].tolist())


def test_packs_lie_over_the_jar_in_order(tmp_path):
    jar = pf.write(tmp_path / "client.jar", jar=True)
    a = over(tmp_path, "a.zip", (1, 100, 1), zipped=True)
    b = over(tmp_path, "b", (2, 200, 2), zipped=False)
    assert stone(Stack.open([jar])) == tuple(pf.texture("stone")[8, 8, :3].tolist())
    assert stone(Stack.open([jar, a, b])) == (2, 200, 2)
    assert stone(Stack.open([jar, b, a])) == (1, 100, 1)
    # the jar is the bottom wherever it is named; what a pack lacks comes from below
    s = Stack.open([a, jar])
    assert stone(s) == (1, 100, 1) and [p for p in s.paths] == [str(jar), str(a)]
    assert Resources(s).texture("minecraft:block/dirt") is not None
    assert Resources(Stack.open([a])).texture("minecraft:block/dirt") is None


def test_a_pack_zipped_inside_its_folder_reads(tmp_path):
    p = tmp_path / "wrapped.zip"
    with zipfile.ZipFile(p, "w") as z:
        z.writestr("MyPack/pack.mcmeta", "{}")
        z.writestr("MyPack/" + STONE, pf.png_bytes(pf.solid((9, 9, 9))))
    assert stone(Stack.open([pf.write(tmp_path / "c.jar", jar=True), p])) == (9, 9, 9)


def test_bad_packs_are_one_line_errors(tmp_path):
    (tmp_path / "empty").mkdir()
    (tmp_path / "notzip.zip").write_bytes(b"hello")
    other = tmp_path / "other.zip"
    with zipfile.ZipFile(other, "w") as z:
        z.writestr("readme.txt", "x")
    for spec, msg in ((tmp_path / "missing", "no such"), (tmp_path / "empty", "not a resource pack"),
                      (tmp_path / "notzip.zip", "not a zip"), (other, "not a resource pack")):
        with pytest.raises(VoxelError, match=msg):
            Stack.open([spec])


@pytest.mark.parametrize("zipped", [True, False])
def test_an_oversized_file_is_refused(tmp_path, monkeypatch, zipped):
    from voxel_addon.mcres import stack as st
    p = over(tmp_path, "big.zip" if zipped else "big", (5, 5, 5), zipped=zipped)
    monkeypatch.setattr(st, "MAX_FILE", len(Stack.open([p]).read(STONE)) - 1)
    with pytest.raises(VoxelError, match="over"):
        Stack.open([p]).read(STONE)


def make_launcher(root, versions):
    for i, v in enumerate(versions):
        d = root / "versions" / v
        d.mkdir(parents=True)
        pf.write(d / f"{v}.jar", jar=True)
        os.utime(d / f"{v}.jar", (1000 + i, 1000 + i))
    (root / "versions" / "no-jar").mkdir()


@pytest.mark.parametrize("platform", ["linux", "win32", "darwin"])
def test_the_launcher_folders_give_the_newest_release(tmp_path, platform):
    env = {"APPDATA": str(tmp_path / "Roaming")}
    root = launcher_dirs(tmp_path, env, platform)[0]
    assert str(root).startswith(str(tmp_path))
    make_launcher(root, ["1.9", "1.21.4", "24w14a", "1.20.1"])
    jars = discover(tmp_path, env, platform)
    assert [j.parent.name for j in jars] == ["1.21.4", "1.20.1", "1.9", "24w14a"]
    s = Stack.open(["minecraft"], tmp_path, env, platform)
    assert s.paths == [str(jars[0])] and s.sources[0].jar


def test_no_jar_in_the_launcher_folders_says_where_it_looked(tmp_path):
    with pytest.raises(VoxelError, match=r"no Minecraft jar found.*\.minecraft"):
        Stack.open(["minecraft"], tmp_path, {}, "linux")
