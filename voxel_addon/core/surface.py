"""What a column looks like from far away: its ground height and block, water and
tree cover (far terrain, far/README.md). One definition, used on stored chunks
(far/) and by generators that know their surface without making chunks.

Every block is one class: ground (what the far heightfield is made of), water,
tree (leaves and logs: the canopy, drawn as cover over the ground), plant (small
cut-outs: invisible from far) or none (air).
"""
from __future__ import annotations

import numpy as np

from .blocks import REGISTRY

CLASSES = ("none", "ground", "water", "tree", "plant")
NONE, GROUND, WATER, TREE, PLANT = range(5)
_TREES = ("leaves", "log")


def _class(b) -> int:
    if b.shape == "none":
        return NONE
    if b.animation == "water":
        return WATER
    if b.name in _TREES:
        return TREE
    if b.shape in ("x", "hash"):
        return PLANT
    return GROUND


CLASS = np.array([_class(b) for b in REGISTRY.blocks], np.uint8)  # by block id


def columns(blocks: np.ndarray) -> dict:
    """Per column of a (..., 256) block array: "height" (top ground z, -1: none),
    "top" (that block's id, 0: none), "water" (top water z above the ground, -1:
    none), "tree" (bool: a leaf or log is the highest non-plant block)."""
    cls = CLASS[blocks]
    zs = np.arange(blocks.shape[-1], dtype=np.int32)

    def highest(mask):
        return np.where(mask, zs, -1).max(axis=-1).astype(np.int32)

    h = highest(cls == GROUND)
    top = np.take_along_axis(blocks, np.maximum(h, 0)[..., None], axis=-1)[..., 0]
    top = np.where(h >= 0, top, 0).astype(np.int32)
    water = highest(cls == WATER)
    water = np.where(water > h, water, -1)
    tree = highest(cls == TREE)
    return {"height": h, "top": top, "water": water, "tree": (tree > h) & (tree > water)}
