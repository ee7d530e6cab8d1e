"""The Overworld (thesis §4.4, fig. 5.3) written in the pass language.

Passes: (1) 2D climate and height map, eq. 4.2; (2) 2D surface materials from the
height map's slope; (3) 3D rock, caves, ore, water, writing `ent` (is the ground
voxel carved by a cave?) from the invocation at ground level; (4) 2D trees: the
trees whose crown reaches each column, read at their root columns; (5) 3D plants:
logs, leaves, flowers, grass, wheat, mushrooms, cactus, glowing mushrooms.
Everything depends only on world coordinates, so chunks are seamless in any order.
"""
from __future__ import annotations

import numpy as np

from ..core.blocks import REGISTRY
from .lang import (Program, absolute, clamp, clamp01, coarse, ifloor, irand2, max_, min_, octaves,
                   perlin2, perlin3, rand2, rand3, select, smoothstep, voronoi2)
from .passgen import PassGenerator

B = {n: REGISTRY.id(n) for n in REGISTRY.names()}
TREE_CELL = 8      # tree grid (thesis: trees on a Voronoi grid, 0..N per cell)
TREE_SLOTS = 2     # N
TREE_REACH = 3     # crown radius bound: how far a tree reaches from its trunk
KEEP = 3           # trees remembered per column
# far terrain: share of a column's area under crowns per unit of treeRate (measured
# on generated chunks: tests/far/test_consistency.py checks it stays close)
TREE_COVER = 0.45
CELL = (4, 4, 4)   # version 2's cave lattice (x, y, z voxels per cell): see README


class OverworldGenerator(PassGenerator):
    name = "overworld"
    # 1: the cave noise per voxel; 2: sampled on a CELL lattice and interpolated, and the
    # mountain and dune Voronoi only where those biomes are (issue 29; the height map, so
    # surface() and far terrain, is version 1's: generation/README.md)
    version = 2
    versions = (1, 2)
    defaults = {
        "sea_level": 62,
        "snow_line": 150,     # snow above this (plus noise)
        "ocean": 0.0,         # raise for more ocean, lower for more land
        "mountains": 1.0,     # mountain height factor
        "trees": 1.0,         # tree density factor
        "caves": 1.0,         # 0 disables caves
        "rivers": 1.0,        # river width factor, 0 disables
    }

    surface_fields = ("groundZ", "top", "treeRate")

    def surface_from(self, f):
        s = super().surface_from(f)
        # trees grow on grass above the sea (pass 4)
        ok = (s["top"] == B["grass"]) & (s["height"] > int(self.params["sea_level"]))
        s["trees"] = np.where(ok, np.clip(f["treeRate"] * TREE_COVER, 0, 1), 0).astype(np.float32)
        return s

    def program(self) -> Program:
        P = self.params
        sea = int(P["sea_level"])
        g = Program("overworld")

        with g.pass2d() as p:  # (1) biome factors and the height map, eq. 4.2
            x, y = p.x, p.y
            e_ocean = octaves(perlin2, (x / 1500, y / 1500), n=3) * 1.6 - 0.22 + float(P["ocean"])
            land = clamp01(e_ocean * -4.0)
            mountainess = smoothstep(0.02, 0.3, octaves(perlin2, (x / 1100, y / 1100), n=2)) * land
            desertness = smoothstep(0.08, 0.25, octaves(perlin2, (x / 1300, y / 1300), n=2)) \
                * (1.0 - mountainess)
            hilliness = clamp01(octaves(perlin2, (x / 600, y / 600), n=2) * 2.5 + 0.3)
            tree_rate = clamp01(octaves(perlin2, (x / 350, y / 350), n=2) * 3.0 + 0.45) \
                * (1.0 - desertness) * float(P["trees"])

            z_ocean = sea - 2 - e_ocean * 70.0 + perlin2(x / 40, y / 40) * 3.0
            z_base = sea - 2 + land * (5.0 + 7.0 * clamp01(octaves(perlin2, (x / 500, y / 500), n=2) + 0.5))
            z_plains = octaves(perlin2, (x / 70, y / 70), n=2) * 4.0
            z_hills = (octaves(perlin2, (x / 110, y / 110), n=3) * 30.0 + 8.0) * hilliness * land
            # mountains: big Voronoi = peaks and ridges, small = folding, Perlin = roughness
            big = voronoi2(x / 230, y / 230).f1
            peaks = clamp01(big * 1.6 - 0.25)
            fold = voronoi2(x / 45, y / 45).f1
            rough = octaves(perlin2, (x / 24, y / 24), n=2) * 10.0
            z_mountains = maximum0(peaks * peaks * 150.0 + fold * fold * 26.0 + rough - 6.0) \
                * mountainess * float(P["mountains"])
            if self.version >= 2:  # Voronoi only where it counts (lazy: cl.py's `if`s)
                z_mountains = select(mountainess > 0.0, z_mountains, 0.0)
            # dunes: max of two Voronoi diagrams of the same size (fig. 4.11)
            d1 = voronoi2(x / 34, y / 34).f1
            d2 = voronoi2((x + 17) / 34, (y - 9) / 34).f1
            dune = max_(d1, d2)
            z_desert = (dune * dune * 12.0 + perlin2(x / 90, y / 90) * 4.0 + 2.0) * desertness * land
            if self.version >= 2:
                z_desert = select(desertness * land > 0.0, z_desert, 0.0)
            # rivers: |Perlin| near zero; bed below sea level, banks lowered towards it
            wx = perlin2(x / 160, y / 160) * 70.0
            wy = perlin2((x + 5000) / 160, y / 160) * 70.0
            r = absolute(octaves(perlin2, ((x + wx) / 900, (y + wy) / 900), n=2, gain=0.35))
            width = (0.014 - 0.007 * mountainess) * float(P["rivers"]) + 1e-6
            t = r / width
            z_rivers = (sea - z_base) + select(t < 1.0, -1.0 - 5.0 * (1.0 - t * t),
                                               (t - 1.0) * (t - 1.0) * 6.0 + (t - 1.0) * 2.0)
            z_land = z_base + min_(z_rivers, max_(z_desert, z_hills, z_mountains, z_plains))
            z = select(e_ocean > 0.0, z_ocean, z_land)
            p.out("groundZ", ifloor(clamp(z, 3.0, 235.0)))
            p.out("ocean", e_ocean)
            p.out("mountain", mountainess)
            p.out("desert", desertness)
            p.out("hills", hilliness * land)
            p.out("treeRate", tree_rate)
            p.out("river", clamp01(1.0 - t) * land)

        with g.pass2d() as p:  # (2) surface materials from height, slope and biome
            gz = p.read("groundZ")
            slope = max_(absolute(p.read("groundZ", 1, 0) - p.read("groundZ", -1, 0)),
                         absolute(p.read("groundZ", 0, 1) - p.read("groundZ", 0, -1)))
            jitter = perlin2(p.x / 12, p.y / 12)
            snow = gz > (int(P["snow_line"]) + jitter * 10.0)
            rocky = ((slope > 4) & (p.read("mountain") > 0.25)) | ((slope > 8) & (p.read("desert") < 0.3))
            rocky = rocky | ((gz > sea + 58 + jitter * 10.0) & (p.read("mountain") > 0.2))
            sandy = (p.read("desert") + jitter * 0.25 > 0.5) | (gz <= sea + 1)
            under = gz < sea - 1
            deep = gz < sea - 7
            top = select(snow, B["snow"], select(rocky, B["stone"],
                         select(deep, B["dirt"], select(sandy | under, B["sand"], B["grass"]))))
            filler = select(rocky | snow, B["stone"], select(sandy | under, B["sand"], B["dirt"]))
            p.out("top", top)
            p.out("filler", filler)
            p.out("fill", 3 + ifloor((jitter + 1.0) * 1.5))
            # cave entrances only where this large 2D noise allows them
            p.out("open", select((perlin2(p.x / 160, p.y / 160) > 0.2) & (gz > sea + 2), 1, 0))

        with g.pass3d() as p:  # (3) rock, caves, ore (water: pass 5)
            x, y, z = p.x, p.y, p.z
            gz = p.read("groundZ")
            p.top(gz)
            depth = gz - z
            # cheap tests first: the OpenCL backend then skips the noise on the right
            # of & wherever the left is false (see cl.py), e.g. cavern outside regions
            cave = (z > 4) & ((depth > 7) | (p.read("open") == 1))
            if self.version >= 2:  # the cave density on a coarse lattice, interpolated
                big = coarse(p, lambda x, y, z: perlin3(x / 140, y / 140, z / 90), CELL)
                small = coarse(p, lambda x, y, z: octaves(perlin3, (x / 42, y / 42, z / 26), n=2),
                               CELL)
            else:  # version 1: per voxel
                big = perlin3(x / 140, y / 140, z / 90)
                small = octaves(perlin3, (x / 42, y / 42, z / 26), n=2)
            cave = cave & (big > 0.18 - 0.1 * float(P["caves"]))
            cave = cave & (small > 0.26)
            if float(P["caves"]) <= 0:
                cave = cave & (z < 0)
            # ore: clumps in a 3-voxel grid, hashed (cheaper than a third 3D noise)
            ore = (depth > 5) & (rand3(x // 3, y // 3, z // 3, salt=50) < 0.03) \
                & (rand3(x, y, z, salt=51) < 0.6)
            ground = select(depth == 0, p.read("top"),
                            select(depth < p.read("fill"), p.read("filler"), B["stone"]))
            p.block(select(cave, B["air"], select(ore, B["ore"], ground)))
            p.column("ent", select(cave, 1, 0), at=gz)

        with g.pass2d() as p:  # (4) trees whose crown may reach this column
            x, y = p.x, p.y
            gz = p.read("groundZ")
            found = [0] * KEEP
            trunk = 0     # kept apart: a crowded column may drop a crown, never a trunk
            count = 0
            tops = max_(gz + 4, sea)
            cx0 = (x - TREE_REACH) // TREE_CELL
            cy0 = (y - TREE_REACH) // TREE_CELL
            for ci in range(4):
                cx, cy = cx0 + ci % 2, cy0 + ci // 2
                for j in range(TREE_SLOTS):
                    kx = cx * TREE_SLOTS + j
                    # slot j roots in its own strip of the cell: two trees never share a trunk
                    rx = cx * TREE_CELL + j * (TREE_CELL // TREE_SLOTS) \
                        + irand2(kx, cy, TREE_CELL // TREE_SLOTS, salt=101)
                    ry = cy * TREE_CELL + irand2(kx, cy, TREE_CELL, salt=102)
                    h = 4 + irand2(kx, cy, 4, salt=103)
                    dx, dy = rx - x, ry - y
                    at = dict(dx=dx, dy=dy, reach=TREE_REACH)
                    rz = p.read("groundZ", **at)
                    ok = ((absolute(dx) <= TREE_REACH) & (absolute(dy) <= TREE_REACH)
                          & (rand2(kx, cy, salt=104) < p.read("treeRate", **at) * 0.9)
                          & (p.read("top", **at) == B["grass"]) & (p.read("ent", **at) == 0)
                          & (rz > sea) & (rz < 200))
                    code = (dx + 4) + (dy + 4) * 8 + h * 64 + rz * 1024   # > 0
                    for s in range(KEEP):
                        found[s] = select(ok & (count == s), code, found[s])
                    count = count + select(ok, 1, 0)
                    trunk = select(ok & (dx == 0) & (dy == 0), code, trunk)
                    tops = select(ok, max_(tops, rz + h + 2), tops)
            for s in range(KEEP):
                p.out(f"tree{s}", found[s])
            p.out("trunk", trunk)
            p.out("vtop", tops)

        with g.pass3d() as p:  # (5) trees and plants
            x, y, z = p.x, p.y, p.z
            gz = p.read("groundZ")
            p.top(p.read("vtop"))
            # water fills oceans and rivers here, so pass 3 stops at the ground
            here = select((z > gz) & (z <= sea), B["water"], p.prev())
            below = p.prev(-1)
            air = here == B["air"]
            out = here
            # vegetation on the ground
            r = rand2(x, y, salt=201)
            tr = p.read("treeRate")
            on_grass = air & (below == B["grass"]) & (z == gz + 1)
            wheat = (perlin2(x / 28, y / 28) > 0.32) & (r < 0.55) & (tr < 0.5)
            plant = select(r < 0.02 + 0.03 * (1.0 - tr), B["flowers"],
                           select(r < 0.32 - 0.2 * tr, B["tall_grass"],
                                  select((r > 0.97) & (tr > 0.4), B["mushroom"], B["air"])))
            out = select(on_grass, select(wheat, B["wheat"], plant), out)
            cactus_h = 1 + irand2(x, y, 3, salt=202)
            cactus = (air & (z > gz) & (z <= gz + cactus_h) & (p.read("top") == B["sand"])
                      & (p.read("desert") > 0.5) & (gz > sea + 1) & (p.read("ent") == 0)
                      & (rand2(x, y, salt=203) < 0.012))
            out = select(cactus, B["cactus"], out)
            glow = air & (z < gz - 6) & (below == B["stone"]) & (rand3(x, y, z, salt=204) < 0.04)
            out = select(glow, B["glowing_mushroom"], out)
            # trees: trunk, then a crown by Manhattan distance with falling probability
            leaves = None
            log = None
            for s in range(KEEP + 1):
                code = p.read(f"tree{s}" if s < KEEP else "trunk")
                dx, dy = code % 8 - 4, (code // 8) % 8 - 4
                h, rz = (code // 64) % 16, code // 1024
                has = code > 0
                if s == KEEP:
                    log = has & (z > rz) & (z <= rz + h)   # the trunk field is this column's
                cz = rz + h
                dist = absolute(dx) + absolute(dy) + absolute(z - cz) * 2
                rad = 3 + select(h > 5, 1, 0)
                prob = clamp01((rad + 0.5 - dist) * 0.45)
                is_leaf = has & (z >= cz - 2) & (z <= cz + 1) & (dist <= rad) \
                    & (rand3(x, y, z, salt=210) < prob + select(dist <= 1, 1.0, 0.0))
                leaves = is_leaf if leaves is None else leaves | is_leaf
            out = select(air & leaves, B["leaves"], out)
            out = select(air & log, B["log"], out)
            p.block(out)
        return g


def maximum0(v):
    return max_(v, 0.0)
