"""The player's Minecraft resources: a resource stack (the client jar, packs over it),
blockstates and block models resolved into element quads in the voxel frame, textures
and biome tints. See README.md; `Resources` is the entry point."""
__all__ = ["Stack", "discover", "Resources", "Quad", "Shape"]
_LAZY = {"Stack": "stack", "discover": "stack", "Resources": "pack", "Quad": "pack", "Shape": "pack"}


def __getattr__(name):   # lazily: an import only needs mcres.states (no models, no images)
    if name in _LAZY:
        from importlib import import_module
        return getattr(import_module(f".{_LAZY[name]}", __name__), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
