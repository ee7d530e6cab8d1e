"""Blockstates: `variants` (keys of property=value, the last matching key wins as in
the game's loader) and `multipart` (`when` with `|` alternatives, `!` negation, `OR`,
`AND`), weighted lists picked by position with the game's own random sequence."""
from __future__ import annotations

from ..core.errors import VoxelError

MASK48 = (1 << 48) - 1
MASK64 = (1 << 64) - 1


def _s64(v: int) -> int:
    v &= MASK64
    return v - (1 << 64) if v >> 63 else v


def _s32(v: int) -> int:
    v &= 0xFFFFFFFF
    return v - (1 << 32) if v >> 31 else v


class JavaRandom:
    """java.util.Random (the game's LegacyRandomSource)."""

    def __init__(self, seed: int):
        self.seed = (seed ^ 0x5DEECE66D) & MASK48

    def next(self, bits: int) -> int:
        self.seed = (self.seed * 0x5DEECE66D + 0xB) & MASK48
        return _s32(self.seed >> (48 - bits))

    def next_long(self) -> int:
        return _s64((self.next(32) << 32) + self.next(32))


def position_seed(x: int, y: int, z: int) -> int:
    """Mth.getSeed: the seed of a block position (Minecraft's frame)."""
    v = _s64(_s32(x * 3129871) ^ _s64(z * 116129781) ^ y)
    v = _s64(v * v * 42317861 + v * 11)
    return v >> 16


def pick(options: list, rnd: JavaRandom):
    """One of OPTIONS (dicts with `weight`) as WeightedBakedModel picks it
    (1.13–1.20: |(int) nextLong()| mod the total weight)."""
    if len(options) == 1:
        return options[0]
    total = sum(o["weight"] for o in options)
    a = abs(_s32(rnd.next_long()))
    # |MIN_VALUE| stays negative in Java, and so does its remainder: the first option
    i = (a % total if a < 1 << 31 else -1) if total > 0 else 0
    for o in options:
        i -= o["weight"]
        if i < 0:
            return o
    return options[0]


def parse_props(key: str) -> dict:
    """`facing=east,half=bottom` → dict; `` or `normal` → {}."""
    if key in ("", "normal"):
        return {}
    out = {}
    for part in key.split(","):
        k, eq, v = part.partition("=")
        if not eq:
            raise VoxelError(f"blockstate key {key!r}: {part!r} is not property=value")
        out[k.strip()] = v.strip()
    return out


def state_key(name: str, props: dict | None) -> str:
    """A block state's one spelling: `minecraft:name[k=v,…]`, properties sorted."""
    name = name if ":" in name else f"minecraft:{name}"
    if not props:
        return name
    return name + "[" + ",".join(f"{k}={props[k]}" for k in sorted(props)) + "]"


def parse_key(key: str) -> tuple[str, dict]:
    """`minecraft:name[k=v,…]` → (name, {k: v})."""
    name, _, rest = key.partition("[")
    return name, (parse_props(rest.rstrip("]")) if rest else {})


def _text(v) -> str:
    return str(v).lower() if isinstance(v, bool) else str(v)


def _options(v, what) -> list:
    """A variant value (one model or a weighted list) → [{model, x, y, uvlock, weight}]."""
    items = v if isinstance(v, list) else [v]
    out = []
    for it in items:
        if not isinstance(it, dict) or not isinstance(it.get("model"), str):
            raise VoxelError(f"{what}: a variant without a model")
        x, y = it.get("x", 0), it.get("y", 0)
        if x not in (0, 90, 180, 270) or y not in (0, 90, 180, 270):
            raise VoxelError(f"{what}: variant rotation x={x}, y={y} is not a multiple of 90")
        w = it.get("weight", 1)
        out.append({"model": it["model"], "x": x, "y": y, "uvlock": bool(it.get("uvlock", False)),
                    "weight": int(w) if isinstance(w, int) and w > 0 else 1})
    if not out:
        raise VoxelError(f"{what}: an empty variant list")
    return out


def matches(when, props: dict, what: str = "multipart") -> bool:
    """A multipart condition against PROPS (strings)."""
    if when is None:
        return True
    if not isinstance(when, dict):
        raise VoxelError(f"{what}: a `when` that is not an object")
    if "OR" in when:
        return any(matches(c, props, what) for c in when["OR"])
    if "AND" in when:
        return all(matches(c, props, what) for c in when["AND"])
    for k, v in when.items():
        v = _text(v)
        neg = v.startswith("!")
        ok = props.get(k) in v.lstrip("!").split("|")
        if ok == neg:
            return False
    return True


class BlockState:
    """One blockstates file."""

    def __init__(self, name: str, j):
        self.name = name
        what = f"blockstate {name}"
        if not isinstance(j, dict):
            raise VoxelError(f"{what}: not a JSON object")
        self.variants = None
        self.parts = None
        if isinstance(j.get("variants"), dict):
            self.variants = [(parse_props(k), _options(v, what)) for k, v in j["variants"].items()]
        elif isinstance(j.get("multipart"), list):
            self.parts = []
            for p in j["multipart"]:
                if not isinstance(p, dict) or "apply" not in p:
                    raise VoxelError(f"{what}: a multipart case without `apply`")
                self.parts.append((p.get("when"), _options(p["apply"], what)))
        else:
            raise VoxelError(f"{what}: neither variants nor multipart")

    def _hit(self, props: dict):
        hit = None
        for key, opts in self.variants:
            if all(props.get(k) == v for k, v in key.items()):
                hit = opts
        return hit

    def choose(self, props: dict, pos=(0, 0, 0)) -> list[dict]:
        """The variants drawn for a block with PROPS at POS (Minecraft's frame)."""
        props = {k: _text(v) for k, v in props.items()}
        rnd = JavaRandom(position_seed(*pos))
        if self.variants is not None:
            hit = self._hit(props)
            return [] if hit is None else [pick(hit, rnd)]
        seed = rnd.next_long()
        return [pick(opts, JavaRandom(seed)) for when, opts in self.parts
                if matches(when, props, f"blockstate {self.name}")]

    def picks(self, props: dict, pos):
        """`choose` for many positions POS (N, 3) (Minecraft's frame) at once: per
        position the index of the drawn option in the matching variant's weighted
        list (the same draw as `pick`); None for a multipart blockstate."""
        import numpy as np
        n = len(pos)
        if self.variants is None:
            return None
        hit = self._hit({k: _text(v) for k, v in props.items()})
        if hit is None or len(hit) == 1:
            return np.zeros(n, np.int64)
        r = np.asarray(pos, np.int64).reshape(-1, 3)
        with np.errstate(over="ignore"):    # uint64 arithmetic wraps as Java's long
            # Mth.getSeed
            v = (r[:, 0] * 3129871).astype(np.int32).astype(np.int64) ^ (r[:, 2] * 116129781) \
                ^ r[:, 1]
            u = v.astype(np.uint64)
            u = u * u * np.uint64(42317861) + u * np.uint64(11)
        return draws(u.view(np.int64) >> 16, [o["weight"] for o in hit])


def draws(seeds, weights):
    """`pick` over options of WEIGHTS with `JavaRandom(seed)` for each of SEEDS (int64):
    the indices drawn. nextLong's low 32 bits are its second `next(32)`."""
    import numpy as np
    total = sum(weights)
    with np.errstate(over="ignore"):
        s = (np.asarray(seeds, np.int64).view(np.uint64) ^ np.uint64(0x5DEECE66D)) \
            & np.uint64(MASK48)
        for _ in range(2):
            s = (s * np.uint64(0x5DEECE66D) + np.uint64(0xB)) & np.uint64(MASK48)
    low = (s >> np.uint64(16)).astype(np.uint32).view(np.int32).astype(np.int64)
    a = np.abs(low)
    i = np.where(a >= 1 << 31, -1, a % total)   # |MIN_VALUE| stays negative in Java
    return np.searchsorted(np.cumsum(weights), i, side="right")
