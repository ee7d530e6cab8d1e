"""A small resource pack written by the tests (the project never ships Minecraft's
files): stairs with variants and uvlock, a multipart fence, a four-model parent chain,
a rotated cross, a tinted grass block with a cutout overlay, tinted cutout leaves,
translucent glass, weighted variants, an animated texture and the two colormaps; and,
with the game's own blockstate and model structure (`mcshapes`), slabs, a glass pane,
a door, a standing torch and rails.

Textures are patterns drawn by code (`packtextures`): `texture(name)` gives a test the
pixels a face should show."""
from __future__ import annotations

import functools
import json
import zipfile
from pathlib import Path

import numpy as np

from voxel_addon.textures import png_bytes

from . import mcshapes, packtextures

MC = "assets/minecraft/"


def solid(rgb, size=16, alpha=255) -> np.ndarray:
    a = np.empty((size, size, 4), np.uint8)
    a[..., :3] = rgb
    a[..., 3] = alpha
    a[0, 0, :3] = (1, 2, 3)        # a marker at the top-left: uv orientation shows
    return a


def texture(name: str) -> np.ndarray:
    """The pixels of the pack's textures/block/NAME.png."""
    return packtextures.all_textures()[name]


def colormap(kind: str) -> np.ndarray:
    """256×256: red = column, green = row, blue = 7 (grass) or 9 (foliage): the pixel
    read shows where the look-up landed."""
    y, x = np.mgrid[0:256, 0:256]
    a = np.empty((256, 256, 4), np.uint8)
    a[..., 0], a[..., 1], a[..., 2], a[..., 3] = x, y, 7 if kind == "grass" else 9, 255
    return a


def _stairs_states() -> dict:
    rot = {"east": 0, "south": 90, "west": 180, "north": 270}
    v = {}
    for facing, y in rot.items():
        for half, x in (("bottom", 0), ("top", 180)):
            v[f"facing={facing},half={half},shape=straight"] = \
                {"model": "block/oak_stairs", "y": y, **({"x": x} if x else {}), "uvlock": True}
    return {"variants": v}


@functools.cache
def _files() -> dict[str, bytes]:
    j = {
        # the parent chain: block → cube → cube_all → stone (textures down, elements up)
        "models/block/block.json": {"ambientocclusion": True, "textures": {"particle": "#all"}},
        "models/block/cube.json": {"parent": "block/block", "elements": [
            {"from": [0, 0, 0], "to": [16, 16, 16], "faces": {
                d: {"texture": f"#{d}", "cullface": d}
                for d in ("down", "up", "north", "south", "west", "east")}}]},
        "models/block/cube_all.json": {"parent": "block/cube", "textures": {
            d: "#all" for d in ("down", "up", "north", "south", "west", "east")}},
        "models/block/stone.json": {"parent": "minecraft:block/cube_all",
                                    "textures": {"all": "minecraft:block/stone"}},
        "models/block/stone_dirt_top.json": {"parent": "block/stone",
                                             "textures": {"up": "block/dirt"}},
        "models/block/stone_mirrored.json": {"parent": "block/cube_all",
                                             "textures": {"all": "block/stone_mirrored"}},
        "blockstates/stone.json": {"variants": {"": [
            {"model": "block/stone", "weight": 3}, {"model": "block/stone_mirrored", "weight": 1},
            {"model": "block/stone", "y": 90}]}},
        # stairs: the step on the east half, as the game's own model
        "models/block/stairs.json": {"parent": "block/block", "elements": [
            {"from": [0, 0, 0], "to": [16, 8, 16], "faces": {
                "down": {"uv": [0, 0, 16, 16], "texture": "#bottom", "cullface": "down"},
                "up": {"uv": [0, 0, 16, 16], "texture": "#top"},
                "north": {"uv": [0, 8, 16, 16], "texture": "#side", "cullface": "north"},
                "south": {"uv": [0, 8, 16, 16], "texture": "#side", "cullface": "south"},
                "west": {"uv": [0, 8, 16, 16], "texture": "#side", "cullface": "west"},
                "east": {"uv": [0, 8, 16, 16], "texture": "#side", "cullface": "east"}}},
            {"from": [8, 8, 0], "to": [16, 16, 16], "faces": {
                "up": {"uv": [8, 0, 16, 16], "texture": "#top", "cullface": "up"},
                "north": {"uv": [0, 0, 8, 8], "texture": "#side", "cullface": "north"},
                "south": {"uv": [8, 0, 16, 8], "texture": "#side", "cullface": "south"},
                "west": {"uv": [0, 0, 16, 8], "texture": "#side"},
                "east": {"uv": [0, 0, 16, 8], "texture": "#side", "cullface": "east"}}}]},
        "models/block/oak_stairs.json": {"parent": "block/stairs", "textures": {
            "bottom": "block/oak_planks", "top": "block/oak_planks", "side": "block/oak_planks"}},
        "blockstates/oak_stairs.json": _stairs_states(),
        # a multipart fence: a post always, an arm per connected side, a cap by OR / AND / !
        "models/block/fence_post.json": {"textures": {"t": "block/oak_planks"}, "elements": [
            {"from": [6, 0, 6], "to": [10, 16, 10], "faces": {
                "up": {"texture": "#t", "cullface": "up"}, "down": {"texture": "#t", "cullface": "down"},
                "north": {"texture": "#t"}, "south": {"texture": "#t"},
                "west": {"texture": "#t"}, "east": {"texture": "#t"}}}]},
        "models/block/fence_side.json": {"textures": {"t": "block/oak_planks"}, "elements": [
            {"from": [7, 12, 0], "to": [9, 15, 9], "faces": {
                "up": {"texture": "#t"}, "down": {"texture": "#t"},
                "north": {"texture": "#t", "cullface": "north"},
                "west": {"texture": "#t"}, "east": {"texture": "#t"}}}]},
        "models/block/fence_cap.json": {"textures": {"t": "block/torch"}, "elements": [
            {"from": [7, 16, 7], "to": [9, 17, 9], "faces": {"up": {"texture": "#t"}}}]},
        "blockstates/oak_fence.json": {"multipart": [
            {"apply": {"model": "block/fence_post"}},
            {"when": {"north": "true"}, "apply": {"model": "block/fence_side", "uvlock": True}},
            {"when": {"east": True}, "apply": {"model": "block/fence_side", "y": 90, "uvlock": True}},
            {"when": {"south": "true"}, "apply": {"model": "block/fence_side", "y": 180, "uvlock": True}},
            {"when": {"west": "true"}, "apply": {"model": "block/fence_side", "y": 270, "uvlock": True}},
            {"when": {"OR": [{"north": "true", "south": "true"}, {"waterlogged": "true"}]},
             "apply": {"model": "block/fence_cap"}},
            {"when": {"AND": [{"east": "!false"}, {"west": "true|maybe"}]},
             "apply": {"model": "block/fence_cap", "x": 180}}]},
        # a cross (flowers) with the game's 45° rescaled planes
        "models/block/cross.json": {"ambientocclusion": False, "elements": [
            {"from": [0.8, 0, 8], "to": [15.2, 16, 8],
             "rotation": {"origin": [8, 8, 8], "axis": "y", "angle": 45, "rescale": True},
             "shade": False, "faces": {"north": {"uv": [0, 0, 16, 16], "texture": "#cross"},
                                       "south": {"uv": [0, 0, 16, 16], "texture": "#cross"}}},
            {"from": [8, 0, 0.8], "to": [8, 16, 15.2],
             "rotation": {"origin": [8, 8, 8], "axis": "y", "angle": 45, "rescale": True},
             "shade": False, "faces": {"west": {"uv": [0, 0, 16, 16], "texture": "#cross"},
                                       "east": {"uv": [0, 0, 16, 16], "texture": "#cross"}}}]},
        "models/block/poppy.json": {"parent": "block/cross", "textures": {"cross": "block/poppy"}},
        "blockstates/poppy.json": {"variants": {"": {"model": "block/poppy"}}},
        # a rotated, face-rotated torch-like element (22.5° about x, no rescale)
        "models/block/torch_wall.json": {"elements": [
            {"from": [7, 3, 14], "to": [9, 13, 16],
             "rotation": {"origin": [8, 3, 16], "axis": "x", "angle": -22.5},
             "faces": {"up": {"uv": [7, 6, 9, 8], "texture": "block/torch", "rotation": 90}}}]},
        "blockstates/wall_torch.json": {"variants": {
            "facing=north": {"model": "block/torch_wall", "y": 0},
            "facing=east": {"model": "block/torch_wall", "y": 90}}},
        # grass: a tinted top, untinted sides, a tinted cutout overlay around them
        "models/block/grass_block.json": {"parent": "block/block", "textures": {
            "bottom": "block/dirt", "top": "block/grass_block_top", "side": "block/grass_block_side",
            "overlay": "block/grass_block_side_overlay"}, "elements": [
            {"from": [0, 0, 0], "to": [16, 16, 16], "faces": {
                "down": {"texture": "#bottom", "cullface": "down"},
                "up": {"texture": "#top", "cullface": "up", "tintindex": 0},
                **{d: {"texture": "#side", "cullface": d} for d in ("north", "south", "west", "east")}}},
            {"from": [0, 0, 0], "to": [16, 16, 16], "faces": {
                d: {"texture": "#overlay", "tintindex": 0, "cullface": d}
                for d in ("north", "south", "west", "east")}}]},
        "blockstates/grass_block.json": {"variants": {"snowy=false": {"model": "block/grass_block"},
                                                      "snowy=true": {"model": "block/stone"}}},
        # drawn by code in the game: a model without elements
        "models/block/chest.json": {"parent": "builtin/entity", "textures": {"particle": "block/oak_planks"}},
        "blockstates/chest.json": {"variants": {"facing=north": {"model": "block/chest"}}},
        # leaves as the game's block/leaves: every face tinted by the foliage colour
        "models/block/leaves.json": {"parent": "block/block", "textures": {"particle": "#all"},
                                     "elements": [{"from": [0, 0, 0], "to": [16, 16, 16], "faces": {
                                         d: {"texture": "#all", "cullface": d, "tintindex": 0}
                                         for d in ("down", "up", "north", "south", "west", "east")}}]},
        "models/block/oak_leaves.json": {"parent": "block/leaves", "textures": {"all": "block/oak_leaves"}},
        "blockstates/oak_leaves.json": {"variants": {"": {"model": "block/oak_leaves"}}},
        "models/block/glass.json": {"parent": "block/cube_all", "textures": {"all": "block/glass"}},
        "blockstates/glass.json": {"variants": {"": {"model": "block/glass"}}},
        "models/block/sea_lantern.json": {"parent": "block/cube_all",
                                          "textures": {"all": "block/sea_lantern"}},
        "blockstates/sea_lantern.json": {"variants": {"": {"model": "block/sea_lantern"}}},
    }
    j.update(mcshapes.files())
    out = {MC + k: json.dumps(v).encode() for k, v in j.items()}
    tex = packtextures.all_textures()
    tex["sea_lantern"] = np.concatenate([solid((10 * i, 40, 90)) for i in range(3)])   # 16×48
    for k, a in tex.items():
        out[MC + f"textures/block/{k}.png"] = png_bytes(a)
    out[MC + "textures/block/sea_lantern.png.mcmeta"] = json.dumps(
        {"animation": {"frametime": 5, "frames": [2, 0, 1]}}).encode()
    for kind in ("grass", "foliage"):
        out[MC + f"textures/colormap/{kind}.png"] = png_bytes(colormap(kind))
    out["pack.mcmeta"] = json.dumps({"pack": {"pack_format": 34, "description": "tests"}}).encode()
    return out


def files() -> dict[str, bytes]:
    return dict(_files())


def write(path: Path, content: dict[str, bytes] | None = None, zipped: bool = False,
          jar: bool = False) -> Path:
    """The pack as a folder, a zip or (JAR) a client-jar-shaped zip."""
    content = files() if content is None else content
    if jar:
        content = {k: v for k, v in content.items() if k != "pack.mcmeta"}
        content["net/minecraft/client/Minecraft.class"] = b"\xca\xfe\xba\xbe"
    if zipped or jar:
        with zipfile.ZipFile(path, "w") as z:
            for k, v in content.items():
                z.writestr(k, v)
        return path
    for k, v in content.items():
        (path / k).parent.mkdir(parents=True, exist_ok=True)
        (path / k).write_bytes(v)
    return path
