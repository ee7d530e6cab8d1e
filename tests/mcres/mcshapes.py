"""Blockstates and models of the test pack laid out as the game lays out its own
(written here, never copied from the game): oak slabs (block/slab, block/slab_top, the
double slab is the planks' cube), a glass pane (the nine-part multipart over
template_glass_pane_post / _side / _side_alt / _noside / _noside_alt), an oak door
(two halves × hinge × open over template_door_*), a standing torch (template_torch)
and rails (block/rail_flat, template_rail_raised_ne / _sw)."""
from __future__ import annotations

SIDES = ("north", "south", "west", "east")


def _slabs() -> dict:
    def slab(lo, hi, top: bool):
        v = [16 - hi, 16 - lo]      # the sides' uv rows: where the slab is in the block
        return {"parent": "block/block", "textures": {"particle": "#side"}, "elements": [{
            "from": [0, lo, 0], "to": [16, hi, 16], "faces": {
                "down": {"uv": [0, 0, 16, 16], "texture": "#bottom",
                         **({} if top else {"cullface": "down"})},
                "up": {"uv": [0, 0, 16, 16], "texture": "#top", **({"cullface": "up"} if top else {})},
                **{d: {"uv": [0, v[0], 16, v[1]], "texture": "#side", "cullface": d} for d in SIDES}}}]}
    tex = {"bottom": "block/oak_planks", "top": "block/oak_planks", "side": "block/oak_planks"}
    return {
        "models/block/slab.json": slab(0, 8, False),
        "models/block/slab_top.json": slab(8, 16, True),
        "models/block/oak_slab.json": {"parent": "block/slab", "textures": tex},
        "models/block/oak_slab_top.json": {"parent": "block/slab_top", "textures": tex},
        "models/block/oak_planks.json": {"parent": "block/cube_all", "textures": {"all": "block/oak_planks"}},
        "blockstates/oak_slab.json": {"variants": {
            "type=bottom": {"model": "minecraft:block/oak_slab"},
            "type=double": {"model": "minecraft:block/oak_planks"},
            "type=top": {"model": "minecraft:block/oak_slab_top"}}},
    }


def _pane() -> dict:
    def el(f, t, faces):
        return {"ambientocclusion": False, "textures": {"particle": "#pane"},
                "elements": [{"from": f, "to": t, "faces": faces}]}
    models = {
        "post": el([7, 0, 7], [9, 16, 9], {
            "down": {"uv": [7, 7, 9, 9], "texture": "#edge"},
            "up": {"uv": [7, 7, 9, 9], "texture": "#edge"}}),
        "side": el([7, 0, 0], [9, 16, 7], {
            "down": {"uv": [7, 0, 9, 7], "texture": "#edge"},
            "up": {"uv": [7, 0, 9, 7], "texture": "#edge"},
            "north": {"uv": [7, 0, 9, 16], "texture": "#edge", "cullface": "north"},
            "west": {"uv": [16, 0, 9, 16], "texture": "#pane"},
            "east": {"uv": [9, 0, 16, 16], "texture": "#pane"}}),
        "side_alt": el([7, 0, 9], [9, 16, 16], {
            "down": {"uv": [7, 9, 9, 16], "texture": "#edge"},
            "up": {"uv": [7, 9, 9, 16], "texture": "#edge"},
            "south": {"uv": [7, 0, 9, 16], "texture": "#edge", "cullface": "south"},
            "west": {"uv": [7, 0, 0, 16], "texture": "#pane"},
            "east": {"uv": [0, 0, 7, 16], "texture": "#pane"}}),
        "noside": el([7, 0, 7], [9, 16, 9], {"north": {"uv": [9, 0, 7, 16], "texture": "#pane"}}),
        "noside_alt": el([7, 0, 7], [9, 16, 9], {"east": {"uv": [7, 0, 9, 16], "texture": "#pane"}}),
    }
    out = {f"models/block/template_glass_pane_{k}.json": v for k, v in models.items()}
    for k in models:
        out[f"models/block/glass_pane_{k}.json"] = {
            "parent": f"minecraft:block/template_glass_pane_{k}",
            "textures": {"pane": "minecraft:block/glass", "edge": "minecraft:block/glass_pane_top"}}
    m = "minecraft:block/glass_pane_"
    out["blockstates/glass_pane.json"] = {"multipart": [
        {"apply": {"model": m + "post"}},
        {"when": {"north": "true"}, "apply": {"model": m + "side"}},
        {"when": {"east": "true"}, "apply": {"model": m + "side", "y": 90}},
        {"when": {"south": "true"}, "apply": {"model": m + "side_alt"}},
        {"when": {"west": "true"}, "apply": {"model": m + "side_alt", "y": 90}},
        {"when": {"north": "false"}, "apply": {"model": m + "noside"}},
        {"when": {"east": "false"}, "apply": {"model": m + "noside_alt"}},
        {"when": {"south": "false"}, "apply": {"model": m + "noside_alt", "y": 90}},
        {"when": {"west": "false"}, "apply": {"model": m + "noside", "y": 270}}]}
    return out


def _door() -> dict:
    """A leaf 3/16 thick on the block's west side; the open and right-hand models are
    the same box with the texture mirrored, the blockstate turns them."""
    def leaf(tex, mirror: bool):
        u, us = ([3, 0, 0, 16], [0, 0, 3, 16])[::-1 if mirror else 1]
        w, e = ([0, 0, 16, 16], [16, 0, 0, 16]) if not mirror else ([16, 0, 0, 16], [0, 0, 16, 16])
        cap = "down" if tex == "#bottom" else "up"
        return {"ambientocclusion": False, "textures": {"particle": "#bottom"}, "elements": [{
            "from": [0, 0, 0], "to": [3, 16, 16], "faces": {
                cap: {"uv": [13, 0, 16, 16], "texture": tex, "cullface": cap},
                "north": {"uv": u, "texture": tex, "cullface": "north"},
                "south": {"uv": us, "texture": tex, "cullface": "south"},
                "west": {"uv": w, "texture": tex, "cullface": "west"},
                "east": {"uv": e, "texture": tex}}}]}
    out = {}
    for half, tex in (("bottom", "#bottom"), ("top", "#top")):
        for hinge in ("left", "right"):
            for opened in ("", "_open"):
                name = f"door_{half}_{hinge}{opened}"
                out[f"models/block/template_{name}.json"] = leaf(tex, (hinge == "right") != bool(opened))
                out[f"models/block/{name}.json"] = {"parent": f"minecraft:block/template_{name}"}
                out[f"models/block/oak_{name}.json"] = {
                    "parent": f"minecraft:block/{name}",
                    "textures": {"bottom": "minecraft:block/oak_door_bottom",
                                 "top": "minecraft:block/oak_door_top"}}
    # the game's turns: closed by facing; open left a quarter clockwise, right anticlockwise
    turn = {"east": 0, "south": 90, "west": 180, "north": 270}
    v = {}
    for facing, y in turn.items():
        for half, part in (("lower", "bottom"), ("upper", "top")):
            for hinge in ("left", "right"):
                for opened in ("false", "true"):
                    yy = y if opened == "false" else (y + (90 if hinge == "left" else 270)) % 360
                    name = f"minecraft:block/oak_door_{part}_{hinge}{'_open' if opened == 'true' else ''}"
                    v[f"facing={facing},half={half},hinge={hinge},open={opened}"] = \
                        {"model": name, **({"y": yy} if yy else {})}
    out["blockstates/oak_door.json"] = {"variants": v}
    return out


def _torch() -> dict:
    return {
        "models/block/template_torch.json": {"ambientocclusion": False, "textures": {"particle": "#torch"},
                                             "elements": [
            {"from": [7, 0, 7], "to": [9, 10, 9], "shade": False, "faces": {
                "down": {"uv": [7, 13, 9, 15], "texture": "#torch"},
                "up": {"uv": [7, 6, 9, 8], "texture": "#torch"}}},
            {"from": [7, 0, 0], "to": [9, 16, 16], "shade": False, "faces": {
                "west": {"uv": [0, 0, 16, 16], "texture": "#torch"},
                "east": {"uv": [0, 0, 16, 16], "texture": "#torch"}}},
            {"from": [0, 0, 7], "to": [16, 16, 9], "shade": False, "faces": {
                "north": {"uv": [0, 0, 16, 16], "texture": "#torch"},
                "south": {"uv": [0, 0, 16, 16], "texture": "#torch"}}}]},
        "models/block/torch.json": {"parent": "minecraft:block/template_torch",
                                    "textures": {"torch": "minecraft:block/torch"}},
        "blockstates/torch.json": {"variants": {"": {"model": "minecraft:block/torch"}}},
    }


def _rails() -> dict:
    def plane(lo, rot=None):
        el = {"from": [0, lo, 0], "to": [16, lo, 16], "faces": {
            "down": {"uv": [0, 16, 16, 0], "texture": "#rail"},
            "up": {"uv": [0, 0, 16, 16], "texture": "#rail"}}}
        if rot is not None:
            el["rotation"] = {"origin": [8, 9, 8], "axis": "x", "angle": rot, "rescale": True}
        return {"ambientocclusion": False, "textures": {"particle": "#rail"}, "elements": [el]}
    m = "minecraft:block/"
    return {
        "models/block/rail_flat.json": plane(1),
        "models/block/template_rail_raised_ne.json": plane(9, 45),
        "models/block/template_rail_raised_sw.json": plane(9, -45),
        "models/block/rail.json": {"parent": m + "rail_flat", "textures": {"rail": m + "rail"}},
        "models/block/rail_raised_ne.json": {"parent": m + "template_rail_raised_ne",
                                             "textures": {"rail": m + "rail"}},
        "models/block/rail_raised_sw.json": {"parent": m + "template_rail_raised_sw",
                                             "textures": {"rail": m + "rail"}},
        "blockstates/rail.json": {"variants": {
            "shape=north_south": {"model": m + "rail"},
            "shape=east_west": {"model": m + "rail", "y": 90},
            "shape=ascending_east": {"model": m + "rail_raised_ne", "y": 90},
            "shape=ascending_west": {"model": m + "rail_raised_sw", "y": 90},
            "shape=ascending_north": {"model": m + "rail_raised_ne"},
            "shape=ascending_south": {"model": m + "rail_raised_sw"}}},
    }


def files() -> dict:
    return {**_slabs(), **_pane(), **_door(), **_torch(), **_rails()}
