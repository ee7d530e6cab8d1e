"""Block models: `parent` chains merged (textures child over parent, `elements` and
`ambientocclusion` from the nearest model that has them), texture variables (`#side`)
resolved, every number checked so a hostile pack gives a one-line error."""
from __future__ import annotations

import json
from dataclasses import dataclass

from ..core.errors import VoxelError
from .geometry import DIRS

MAX_DEPTH = 64               # parents in one chain
MAX_ELEMENTS = 4096


def location(ref: str, kind: str, ext: str) -> str:
    """`ns:path` (or `path`, namespace minecraft) → `assets/ns/KIND/path.EXT`."""
    ns, _, path = ref.rpartition(":")
    return f"assets/{ns or 'minecraft'}/{kind}/{path}{ext}"


def canon(ref: str) -> str:
    return ref if ":" in ref else f"minecraft:{ref}"


def load_json(stack, name: str, what: str):
    data = stack.read(name)
    if data is None:
        return None
    try:
        return json.loads(data.decode("utf-8-sig"))
    except (UnicodeDecodeError, json.JSONDecodeError, RecursionError) as e:
        raise VoxelError(f"{what}: bad JSON in {name} ({str(e)[:80]})") from None


@dataclass
class Model:
    """A model with its parents merged. `textures` maps each face's `#var` already
    resolved: faces carry `sprite` (a texture id or None when the chain leaves it
    unset)."""
    id: str
    elements: list
    ao: bool
    textures: dict


def _num3(v, what):
    if not (isinstance(v, list) and len(v) == 3 and all(isinstance(c, (int, float)) for c in v)):
        raise VoxelError(f"{what}: expected three numbers, got {str(v)[:40]}")
    if not all(-16 <= c <= 32 for c in v):
        raise VoxelError(f"{what}: {v} is outside -16..32")
    return [float(c) for c in v]


def _element(el, what) -> dict:
    if not isinstance(el, dict) or not isinstance(el.get("faces", {}), dict):
        raise VoxelError(f"{what}: an element is not an object")
    out = {"from": _num3(el.get("from"), what), "to": _num3(el.get("to"), what),
           "shade": el.get("shade", True) is not False, "faces": {}}
    r = el.get("rotation")
    if r is not None:
        if not isinstance(r, dict) or r.get("axis") not in ("x", "y", "z") \
                or not isinstance(r.get("angle", 0), (int, float)) or abs(r.get("angle", 0)) > 360:
            raise VoxelError(f"{what}: bad element rotation {str(r)[:60]}")
        out["rotation"] = {"axis": r["axis"], "angle": float(r.get("angle", 0)),
                           "origin": _num3(r.get("origin", [8, 8, 8]), what),
                           "rescale": bool(r.get("rescale", False))}
    for d, face in el.get("faces", {}).items():
        if d not in DIRS or not isinstance(face, dict):
            continue
        uv = face.get("uv")
        if uv is not None and not (isinstance(uv, list) and len(uv) == 4
                                   and all(isinstance(c, (int, float)) for c in uv)):
            raise VoxelError(f"{what}: bad uv {str(uv)[:40]}")
        rot = face.get("rotation", 0)
        if rot not in (0, 90, 180, 270):
            raise VoxelError(f"{what}: face rotation {rot} is not 0, 90, 180 or 270")
        tint = face.get("tintindex", -1)
        out["faces"][d] = {"uv": [float(c) for c in uv] if uv else None,
                           "texture": str(face.get("texture", "")), "rotation": rot,
                           "cullface": face.get("cullface") if face.get("cullface") in DIRS else None,
                           "tintindex": int(tint) if isinstance(tint, (int, float)) else -1}
    return out


def _sprite(v):
    """A textures entry: a string, or (1.21.6+) {"sprite": ...}."""
    if isinstance(v, dict):
        v = v.get("sprite")
    return v if isinstance(v, str) else None


def resolve(textures: dict, ref: str) -> str | None:
    """`#var` through TEXTURES (bounded: a cycle resolves to None) → a texture id."""
    for _ in range(32):
        if not ref.startswith("#"):
            return canon(ref) if ref else None
        ref = textures.get(ref[1:])
        if ref is None:
            return None
    return None


def load(stack, ref: str) -> Model | None:
    """Model REF with its parents; None when the pack has no such model."""
    chain, seen, cur = [], set(), canon(ref)
    while cur is not None:
        if cur in seen:
            raise VoxelError(f"model {ref}: parent cycle through {cur}")
        if len(chain) >= MAX_DEPTH:
            raise VoxelError(f"model {ref}: more than {MAX_DEPTH} parents")
        seen.add(cur)
        if cur.startswith("minecraft:builtin/"):
            break
        j = load_json(stack, location(cur, "models", ".json"), f"model {ref}")
        if j is None:
            if not chain:
                return None
            break      # a missing parent: what the children give is kept
        if not isinstance(j, dict):
            raise VoxelError(f"model {cur}: not a JSON object")
        chain.append(j)
        p = j.get("parent")
        cur = canon(p) if isinstance(p, str) else None
    textures, elements, ao = {}, None, None
    for j in reversed(chain):       # root first, children over it
        t = j.get("textures", {})
        if isinstance(t, dict):
            textures.update({k: s for k, v in t.items() if (s := _sprite(v)) is not None})
    for j in chain:                 # the nearest one that has them
        if elements is None and isinstance(j.get("elements"), list):
            elements = j["elements"]
        if ao is None and isinstance(j.get("ambientocclusion"), bool):
            ao = j["ambientocclusion"]
    elements = elements or []
    if len(elements) > MAX_ELEMENTS:
        raise VoxelError(f"model {ref}: more than {MAX_ELEMENTS} elements")
    els = [_element(e, f"model {ref}") for e in elements]
    for e in els:
        for face in e["faces"].values():
            face["sprite"] = resolve(textures, face["texture"])
    return Model(canon(ref), els, True if ao is None else ao, textures)
