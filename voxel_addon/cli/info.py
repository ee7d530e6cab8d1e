"""info: the world's metadata and block table as JSON (SPEC §5)."""
from __future__ import annotations

import json

from .common import add_world


def add_parser(sub):
    p = sub.add_parser("info", help="print world metadata as JSON")
    add_world(p)
    return p


def run(args):
    from ..core.blocks import REGISTRY
    from ..storage import WorldFile
    wf = WorldFile(args.world, readonly=True)
    try:
        m = wf.meta
        codecs = dict(wf.db.execute("SELECT codec, COUNT(*) FROM chunks GROUP BY codec"))
        out = {
            "format_version": int(m["format_version"]),
            "seed": wf.seed,
            "generator": wf.generator,
            "generator_version": wf.generator_version,
            "generator_params": wf.generator_params,
            "chunks": wf.chunk_count(),
            "edits": wf.edit_count(),
            "codecs": codecs,
            "file_bytes": args.world.stat().st_size,
            "block_types": REGISTRY.describe(),
        }
        from ..storage import minecraft as mcfile
        if m.get(mcfile.STATES):   # a Minecraft import kept states (issue 30)
            out["minecraft"] = {
                "states": max(len(json.loads(m[mcfile.STATES])) - 1, 0),
                "biomes": mcfile.names(m),
                "resources": json.loads(m.get(mcfile.RESOURCES) or "null"),
                "y_min": int(m.get(mcfile.Y_MIN) or 0)}
    finally:
        wf.close()
    print(json.dumps(out, indent=1))
