"""What a Minecraft import keeps for the resource stack (issue 30): each voxel's block
state (the world's state palette, the index in the small data), the `color` block's
colour per dye state, each column's biome (1.18+ section palettes, 1.15–1.17 cells,
older columns), and the stack's paths; written with the chunks, stable over a second
import."""
from __future__ import annotations

import json

import numpy as np
import pytest

from voxel_addon.core import colors
from voxel_addon.core.blocks import REGISTRY
from voxel_addon.formats import mcstate, minecraft
from voxel_addon.storage import minecraft as mcbiomes
from voxel_addon.world import World

from . import mcfiles as mc

AIR = "minecraft:air"
STAIR_E = "minecraft:oak_stairs[facing=east,half=bottom,shape=straight,waterlogged=false]"
STAIR_N = "minecraft:oak_stairs[facing=north,half=top,shape=straight,waterlogged=false]"


def voxel(x, y, z, y_min=-64):
    """Minecraft block → voxel (formats/README)."""
    return x, -1 - z, y - y_min


def build(version=3953):
    """One chunk (0, 0): stone floor at y 0, two stairs, white wool and a white carpet,
    grass; 1.18+ biomes: desert where x < 4 in the floor's section, forest above."""
    a = np.full((16, 16, 16), AIR, object)
    a[0] = "minecraft:stone"
    a[1, 2, 3] = STAIR_E
    a[1, 5, 6] = STAIR_N
    a[1, 7, 7] = "minecraft:white_wool"
    a[2, 7, 7] = "minecraft:white_carpet"
    a[1, 9, 9] = "minecraft:grass_block[snowy=false]"
    a[5, 12, 1] = "minecraft:oak_leaves[distance=1,persistent=true,waterlogged=false]"
    cells = np.zeros((4, 4, 4), int)           # [y][z][x]
    cells[:, :, 0] = 1                           # x 0..3: desert
    biomes = {0: (["minecraft:forest", "minecraft:desert"], cells.reshape(-1))}
    return {0: a}, biomes


def imported(tmp_path, chunks, version=3953, **kw):
    save = tmp_path / "save"
    mc.write_region(save / "region", chunks)
    w = tmp_path / "w.sqlite"
    with World.create(w, seed=0, generator="empty", loader=False) as world:
        rep = minecraft.import_world(world, save, **kw)
    return w, rep


def state_at(world, x, y, z, y_min=-64):
    """(block name, state, small data) of a Minecraft block, its state as the readers
    see it (storage/minecraft.py states)."""
    meta = world.file.meta
    states = json.loads(meta[mcstate.KEY])
    vx, vy, vz = voxel(x, y, z, y_min)
    c = world.chunk_at(vx >> 4, vy >> 4)
    d = 0 if c.data is None else int(c.data[vx & 15, vy & 15, vz])
    b = REGISTRY[int(c.blocks[vx & 15, vy & 15, vz])].name
    cstates = {int(k): v for k, v in json.loads(meta.get(mcstate.COLOR_KEY) or "{}").items()}
    st = mcbiomes.states(c.blocks[vx & 15, vy & 15, vz:vz + 1], None if c.data is None else
                         c.data[vx & 15, vy & 15, vz:vz + 1], states, cstates,
                         REGISTRY.id("color"), mcbiomes.defaults(meta))
    return b, states[int(st[0])], d


def test_states_biomes_and_resources_are_kept(tmp_path):
    secs, biomes = build()
    w, rep = imported(tmp_path, {(0, 0): mc.chunk_nbt(0, 0, secs, biomes=biomes)},
                      resources=["/packs/client.jar", "/packs/faithful.zip"])
    assert rep.chunks == 1
    with World.open(w, loader=False, readonly=True) as world:
        assert json.loads(world.file.meta[mcstate.RESOURCES]) == ["/packs/client.jar",
                                                                  "/packs/faithful.zip"]
        assert state_at(world, 3, 1, 2)[1] == STAIR_E
        assert state_at(world, 6, 1, 5)[1] == STAIR_N
        assert state_at(world, 0, 0, 0)[1] == "minecraft:stone"
        assert state_at(world, 9, 1, 9)[1] == "minecraft:grass_block[snowy=false]"
        assert state_at(world, 0, 3, 0) == ("air", "", 0)
        # wool and carpet: both the colour block, same colour, each its own entry
        wool, carpet = state_at(world, 7, 1, 7), state_at(world, 7, 2, 7)
        assert wool[:2] == ("color", "minecraft:white_wool")
        assert carpet[:2] == ("color", "minecraft:white_carpet") and wool[2] != carpet[2]
        pal = colors.parse(world.file.meta)
        assert pal[wool[2]].tolist() == pal[carpet[2]].tolist()
        # biomes: the column's top block decides; x < 4 desert, the rest forest
        names = mcbiomes.names(world.file.meta)
        cols = mcbiomes.read(world.file, (0, -1))
        top = {(lx, ly): names[cols[lx, ly]] for lx in range(16) for ly in range(16)}
        assert {top[(x, 15 - z)] for x in range(4) for z in range(16)} == {"minecraft:desert"}
        assert {top[(x, 15 - z)] for x in range(4, 16) for z in range(16)} == {"minecraft:forest"}
        assert mcbiomes.read(world.file, (5, 5)) is None


def test_a_column_takes_the_biome_of_its_top_block(tmp_path):
    """Leaves at y 5 (cell y 1) in a column whose lower cells are another biome;
    jungle only in the cells of z 12..15 from y 4 up."""
    a = np.full((16, 16, 16), AIR, object)
    a[0] = "minecraft:stone"
    a[5, 12, 1] = "minecraft:oak_leaves"
    cells = np.zeros((4, 4, 4), int)
    cells[1:, 3] = 1
    w, _ = imported(tmp_path, {(0, 0): mc.chunk_nbt(0, 0, {0: a}, biomes={
        0: (["minecraft:plains", "minecraft:jungle"], cells.reshape(-1))})})
    with World.open(w, loader=False, readonly=True) as world:
        names = mcbiomes.names(world.file.meta)
        cols = mcbiomes.read(world.file, (0, -1))
        assert names[cols[1, 15 - 12]] == "minecraft:jungle"
        assert names[cols[2, 15 - 12]] == "minecraft:plains"
        assert {names[v] for v in cols.ravel()} == {"minecraft:plains", "minecraft:jungle"}


@pytest.mark.parametrize("version, size", [(2730, 1024), (1976, 256)])
def test_older_biome_arrays(tmp_path, version, size):
    """1.15–1.17: 1024 cells (y, z, x by fours); before: 256 columns (z, x);
    numeric ids, 1.18's names (3 'mountains' → windswept_hills)."""
    a = np.full((16, 16, 16), AIR, object)
    a[0] = "minecraft:stone"
    ids = np.full(size, 1)                       # plains
    if size == 256:
        ids.reshape(16, 16)[:, 8:] = 2            # x >= 8: desert
    else:
        ids.reshape(64, 4, 4)[:, :, 2:] = 3       # x >= 8: mountains
    w, rep = imported(tmp_path, {(0, 0): mc.chunk_nbt(0, 0, {0: a}, version=version,
                                                      old_biomes=ids)})
    assert rep.chunks == 1 and rep.y_min == 0
    with World.open(w, loader=False, readonly=True) as world:
        names = mcbiomes.names(world.file.meta)
        cols = mcbiomes.read(world.file, (0, -1))
        east = "minecraft:desert" if size == 256 else "minecraft:windswept_hills"
        assert {names[v] for v in cols[8:].ravel()} == {east}
        assert {names[v] for v in cols[:8].ravel()} == {"minecraft:plains"}


def test_a_second_import_keeps_the_palette(tmp_path):
    secs, biomes = build()
    save = tmp_path / "save"
    mc.write_region(save / "region", {(0, 0): mc.chunk_nbt(0, 0, secs, biomes=biomes)})
    w = tmp_path / "w.sqlite"
    with World.create(w, seed=0, generator="empty", loader=False) as world:
        minecraft.import_world(world, save)
        first = world.file.meta[mcstate.KEY], world.file.meta[colors.KEY]
        minecraft.import_world(world, save, replace=True)
        assert (world.file.meta[mcstate.KEY], world.file.meta[colors.KEY]) == first
    with World.open(w, loader=False, readonly=True) as world:
        assert state_at(world, 3, 1, 2)[1] == STAIR_E


def test_state_keys_round_trip():
    k = mcstate.state_key("oak_stairs", {"half": "top", "facing": "east"})
    assert k == "minecraft:oak_stairs[facing=east,half=top]"
    assert mcstate.parse_key(k) == ("minecraft:oak_stairs", {"facing": "east", "half": "top"})
    assert mcstate.parse_key("minecraft:stone") == ("minecraft:stone", {})


def test_cli_resources_are_checked_and_kept(tmp_path, capsys):
    from voxel_addon.cli import main
    from tests.mcres import packfiles as pf
    secs, biomes = build()
    save = tmp_path / "save"
    mc.write_region(save / "region", {(0, 0): mc.chunk_nbt(0, 0, secs, biomes=biomes)})
    jar = pf.write(tmp_path / "client.jar", jar=True)
    pack = tmp_path / "pack"
    pack.mkdir()
    pf.write(pack, {"pack.mcmeta": b"{}"})
    w = tmp_path / "w.sqlite"
    # a bad pack: one line, before the world is made
    assert main(["import", "--world", str(w), "--from", str(save), "--resources", str(jar),
                 "--resources", str(tmp_path / "nope.zip")]) == 2
    err = capsys.readouterr().err.strip()
    assert "nope.zip" in err and len(err.splitlines()) == 1 and not w.exists()
    # the pack named first still lies over the jar
    assert main(["import", "--world", str(w), "--from", str(save), "--resources", str(pack),
                 "--resources", str(jar)]) == 0
    with World.open(w, loader=False, readonly=True) as world:
        assert json.loads(world.file.meta[mcstate.RESOURCES]) == [str(jar.resolve()),
                                                                  str(pack.resolve())]
    capsys.readouterr()
    assert main(["info", "--world", str(w)]) == 0
    got = json.loads(capsys.readouterr().out)["minecraft"]
    assert got["resources"] == [str(jar.resolve()), str(pack.resolve())] and got["y_min"] == -64
    assert got["states"] == 7 and set(got["biomes"]) == {"minecraft:plains", "minecraft:forest",
                                                          "minecraft:desert"}


def test_columns_match_a_plain_loop_over_columns():
    """mcstate.columns (tops from the span below the highest block, lookups per top
    layer) against a loop over each column: random heights, holes, empty columns,
    sections with biomes here and there (nearest one taken), y_min moved."""
    from types import SimpleNamespace as NS
    from voxel_addon.core import chunk as C
    from voxel_addon.formats.anvil import cells
    rng = np.random.default_rng(3)
    names = [f"minecraft:b{i}" for i in range(5)]
    for t in range(60):
        b = C.empty()
        ground = int(rng.integers(1, 200)) if t % 3 else 0   # most: every column has a block
        b[:, :, :ground] = 1
        for _ in range(rng.integers(0, 6)):
            x0, y0 = rng.integers(0, 16, 2)
            z1 = int(rng.integers(ground, min(ground + 48, 256) + 1)) if ground else int(rng.integers(0, 257))
            b[x0:, y0:, int(rng.integers(0, z1 + 1)):z1] = rng.integers(0, 3)
        secs = []
        for y in sorted(set(rng.integers(-4, 20, rng.integers(1, 6)).tolist())):
            k = int(rng.integers(1, 4))
            per = 64 // max(1, (k - 1).bit_length())
            data = None if k == 1 else rng.integers(0, 2 ** 62, -(-64 // per)).astype(">i8")
            secs.append(NS(y=y, biomes=(list(rng.choice(names, k, replace=False)), data)))
        y_min = int(rng.choice([-64, 0, -32]))
        index: dict = {}
        got = mcstate.columns(NS(biomes=None, sections=secs), b, y_min,
                              lambda n: index.setdefault(n, len(index)), {})
        by = {s.y: s.biomes for s in secs}
        for lx in range(16):
            for ly in range(16):
                solid = np.flatnonzero(b[lx, ly])
                y = (int(solid[-1]) if len(solid) else 0) + y_min
                sy = min(max(y >> 4, min(by)), max(by))
                near = min(by, key=lambda v: abs(v - sy))
                c = cells(by[near])
                cell = ((y & 15) >> 2) * 16 + ((15 - ly) >> 2) * 4 + (lx >> 2)
                want = by[near][0][0 if c is None else int(c[cell])]
                assert got[lx, ly] == index[want], (t, lx, ly)
