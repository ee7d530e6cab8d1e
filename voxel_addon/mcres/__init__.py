"""The player's Minecraft resources: a resource stack (the client jar, packs over it),
blockstates and block models resolved into element quads in the voxel frame, textures
and biome tints. See README.md; `Resources` is the entry point."""
from .stack import Stack, discover
from .pack import Resources, Quad, Shape

__all__ = ["Stack", "discover", "Resources", "Quad", "Shape"]
