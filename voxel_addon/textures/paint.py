"""Painters: one function per texture name, each drawing a seeded 16×16 RGBA tile.

Every painter gets `rng` (a NumPy Generator seeded from the world-independent
texture seed and the name) and returns (rgba (16,16,4) uint8, glow (16,16) uint8).
Row 0 is the top of the image. Opaque textures tile seamlessly (noise wraps), so
merged faces with REPEAT UVs show no seams.
"""
from __future__ import annotations

import numpy as np

N = 16
_yy, _xx = np.mgrid[0:N, 0:N]


# ---------------------------------------------------------------- helpers

def noise(rng, cells: int) -> np.ndarray:
    """Tileable smooth value noise in [0, 1] from a cells×cells random lattice."""
    g = rng.random((cells, cells))
    t = (np.arange(N) + 0.5) * cells / N - 0.5
    i0 = np.floor(t).astype(int)
    f = t - i0
    f = f * f * (3 - 2 * f)  # smoothstep: no visible lattice creases
    i0 %= cells
    i1 = (i0 + 1) % cells
    rows = g[i0] * (1 - f)[:, None] + g[i1] * f[:, None]
    return rows[:, i0] * (1 - f)[None, :] + rows[:, i1] * f[None, :]


def fbm(rng, cells=(2, 4, 8, 16), amps=(0.45, 0.3, 0.15, 0.1)) -> np.ndarray:
    v = sum(a * (noise(rng, c) if c < N else rng.random((N, N))) for c, a in zip(cells, amps))
    lo, hi = v.min(), v.max()
    return (v - lo) / max(hi - lo, 1e-6)


def hexes(*codes: str) -> np.ndarray:
    return np.array([[int(c[i:i + 2], 16) for i in (0, 2, 4)] for c in codes], np.float32)


def ramp(v: np.ndarray, palette: np.ndarray) -> np.ndarray:
    """Quantise v in [0, 1] onto a dark→light palette: the pixel-art look."""
    k = np.clip((v * len(palette)).astype(int), 0, len(palette) - 1)
    return palette[k]


def rgba(rgb: np.ndarray, alpha=255) -> np.ndarray:
    out = np.empty((N, N, 4), np.uint8)
    out[..., :3] = np.clip(np.rint(rgb), 0, 255)
    out[..., 3] = alpha
    return out


def clear() -> np.ndarray:
    return np.zeros((N, N, 4), np.uint8)


def put(img, y, x, rgb, a=255):
    if 0 <= y < N and 0 <= x < N:
        img[y, x, :3] = rgb
        img[y, x, 3] = a


def no_glow() -> np.ndarray:
    return np.zeros((N, N), np.uint8)


# ---------------------------------------------------------------- ground

STONE = hexes("5d5d62", "6e6e73", "7d7d82", "8b8b90", "9a9a9e")
DIRT = hexes("5a3b22", "6b4629", "7a5231", "8a5f3a", "9a6d45")
GRASS = hexes("3d6e22", "4a8029", "579232", "66a23b", "7cb648")
SNOW = hexes("c9d6e3", "dbe5ef", "e9f0f7", "f6f9fc")
SAND = hexes("cbb57c", "d6c28a", "e0cd96", "e8d7a4", "efe0b4")


def stone(rng):
    v = fbm(rng)
    rgb = ramp(v, STONE)
    # a few dark crack pixels where the noise folds (thin ridges of a second field)
    r = np.abs(noise(rng, 4) - 0.5)
    rgb[r < 0.03] = STONE[0] * 0.85
    return rgba(rgb), no_glow()


def dirt(rng):
    v = fbm(rng, amps=(0.35, 0.3, 0.2, 0.15))
    rgb = ramp(v, DIRT)
    specks = rng.random((N, N))
    rgb[specks < 0.05] = DIRT[0] * 0.8
    rgb[specks > 0.97] = hexes("a08a70")[0]  # pebbles
    return rgba(rgb), no_glow()


def grass_top(rng):
    v = fbm(rng, amps=(0.3, 0.25, 0.2, 0.25))
    rgb = ramp(v, GRASS)
    blades = rng.random((N, N))
    rgb[blades > 0.93] = hexes("8fc85a")[0]
    rgb[blades < 0.04] = GRASS[0] * 0.85
    return rgba(rgb), no_glow()


def _side_band(rng, under, top_rgb_fn, depth=(2, 5)):
    """A dirt side with a top band (grass or snow) hanging down irregularly."""
    img, _ = under(rng)
    h = rng.integers(depth[0], depth[1], N)
    # neighbouring columns differ by at most 2 so the drip edge looks organic
    for x in range(1, N):
        h[x] = int(np.clip(h[x], h[x - 1] - 2, h[x - 1] + 2))
    h[-1] = int(np.clip(h[-1], h[0] - 2, h[0] + 2))  # wraps with column 0
    band = _yy < h[None, :]
    top = top_rgb_fn(rng)
    img[band, :3] = top[band]
    return img, no_glow()


def grass_side(rng):
    return _side_band(rng, dirt, lambda r: ramp(fbm(r), GRASS[1:]))


def snow(rng):
    v = fbm(rng, amps=(0.4, 0.3, 0.2, 0.1))
    rgb = ramp(v, SNOW)
    rgb[rng.random((N, N)) > 0.96] = hexes("ffffff")[0]
    return rgba(rgb), no_glow()


def snow_side(rng):
    return _side_band(rng, dirt, lambda r: ramp(fbm(r), SNOW), depth=(3, 6))


def sand(rng):
    v = 0.5 * fbm(rng, amps=(0.3, 0.2, 0.2, 0.3)) + 0.5 * rng.random((N, N))
    rgb = ramp(v, SAND)
    rgb[rng.random((N, N)) < 0.03] = hexes("a8925e")[0]
    return rgba(rgb), no_glow()


def ore(rng):
    img, _ = stone(rng)
    glow = no_glow()
    speck = hexes("d2691e", "f39c12", "ffd35c")
    for _ in range(int(rng.integers(4, 6))):
        cy, cx = rng.integers(1, N - 2, 2)
        for dy, dx in ((0, 0), (0, 1), (1, 0), (1, 1), (-1, 0), (0, -1)):
            if rng.random() < 0.75 or (dy, dx) == (0, 0):
                y, x = (cy + dy) % N, (cx + dx) % N
                k = 2 if (dy, dx) == (0, 0) else int(rng.integers(0, 2))
                img[y, x, :3] = speck[k]
                glow[y, x] = 255 if k == 2 else 170
    return img, glow


# ---------------------------------------------------------------- wood, plants

BARK = hexes("3f2a17", "4e3520", "5d4029", "6d4c31")
WOOD = hexes("9c7a4b", "b08c57", "c4a068", "d3b27a")


def log_side(rng):
    # vertical bark: columns of noise stretched along y
    cols = rng.random(N)
    v = 0.6 * cols[None, :] + 0.4 * noise(rng, 8)
    rgb = ramp(v, BARK)
    for x in rng.choice(N, 4, replace=False):  # deep grooves of varying length
        y0, ln = rng.integers(0, N), rng.integers(5, 12)
        rgb[(np.arange(ln) + y0) % N, x] = BARK[0] * 0.8
    return rgba(rgb), no_glow()


def log_top(rng):
    c = (N - 1) / 2
    d = np.maximum(np.abs(_xx - c), np.abs(_yy - c)) + 0.35 * np.hypot(_xx - c, _yy - c)
    d = d + 0.6 * (noise(rng, 4) - 0.5)
    rings = (np.floor(d / 1.6).astype(int) % 2).astype(np.float32)
    rgb = WOOD[np.clip((rings * 2 + (fbm(rng) > 0.5)).astype(int), 0, 3)]
    border = (np.minimum(np.minimum(_xx, _yy), np.minimum(N - 1 - _xx, N - 1 - _yy)) == 0)
    bark, _ = log_side(rng)
    rgb[border] = bark[border, :3]
    return rgba(rgb), no_glow()


LEAF = hexes("1f4d16", "2a621d", "367826", "458c30", "5aa33c")


def leaves(rng):
    v = fbm(rng, amps=(0.25, 0.35, 0.2, 0.2))
    rgb = ramp(v, LEAF)
    a = np.full((N, N), 255, np.uint8)
    holes = (rng.random((N, N)) < 0.16) & (v < 0.55)  # gaps sit in the dark parts
    a[holes] = 0
    return rgba(rgb, a), no_glow()


def _stem(img, rng, x, top, colour=None):
    col = colour if colour is not None else hexes("3d7a24")[0]
    bend = 0
    for y in range(N - 1, top - 1, -1):
        if rng.random() < 0.15:
            bend += int(rng.choice((-1, 1)))
        put(img, y, int(np.clip(x + bend, 0, N - 1)), col)
    return int(np.clip(x + bend, 0, N - 1))


def flowers(rng):
    img = clear()
    petals = hexes("e8413a", "f2d53c", "c86ce0", "f7f7f7", "ff8a3d")
    for x in (3, 8, 12):
        top = int(rng.integers(4, 8))
        hx = _stem(img, rng, x, top)
        put(img, top + 3, hx - 1, hexes("4f9a2e")[0])  # a leaf
        col = petals[int(rng.integers(0, len(petals)))]
        for dy, dx in ((-1, 0), (1, 0), (0, -1), (0, 1)):
            put(img, top + dy, hx + dx, col)
        put(img, top, hx, hexes("f5c242")[0] if col[0] < 240 or col[1] < 200 else hexes("8a5a1a")[0])
    return img, no_glow()


def tall_grass(rng):
    img = clear()
    shades = GRASS[1:]
    for x in range(1, N - 1, 2):
        x = x + int(rng.integers(0, 2))
        top = int(rng.integers(2, 10))
        lean = rng.choice((-1, 1))
        for i, y in enumerate(range(N - 1, top - 1, -1)):
            xx = x + int(lean * (i > (N - top) * 0.6))
            put(img, y, min(max(xx, 0), N - 1), shades[min(3, i * 4 // (N - top + 1))])
    return img, no_glow()


def wheat(rng):
    img = clear()
    stalk, grain = hexes("a89a3a", "bfae45"), hexes("d9b84a", "e8cc5c", "c49a32")
    for x in (1, 4, 7, 10, 13):
        x += int(rng.integers(0, 2))
        top = int(rng.integers(1, 4))
        for y in range(N - 1, top + 4, -1):
            put(img, y, x, stalk[y % 2])
        for y in range(top, top + 5):  # the ear: a plump two-pixel column
            put(img, y, x, grain[(y + x) % 3])
            if y > top and y < top + 4:
                put(img, y, x + 1, grain[(y + x + 1) % 3])
        put(img, top - 1, x, grain[2])  # awn
    return img, no_glow()


def _mushroom(rng, cap, spot, glows):
    img, glow = clear(), no_glow()
    stem = hexes("e6dcc4", "d2c6aa")
    for y in range(10, N):
        for x in (7, 8):
            put(img, y, x, stem[(x + y) % 2])
    rows = [(6, 5, 10), (7, 4, 11), (8, 3, 12), (9, 3, 12)]  # cap: y, x0, x1 (inclusive)
    for y, x0, x1 in rows:
        for x in range(x0, x1 + 1):
            shade = cap[1] if y < 8 else cap[0]
            put(img, y, x, shade)
            glow[y, x] = 255 if glows else 0
    for y in range(10, 11):
        for x in range(4, 12):
            put(img, y, x, cap[0] * 0.75)  # shadowed underside
    for _ in range(4):
        y, x0, x1 = rows[int(rng.integers(0, 3))]
        put(img, y, int(rng.integers(x0 + 1, x1)), spot)
    if glows:
        glow[img[..., 3] == 0] = 0
    return img, glow


def mushroom(rng):
    return _mushroom(rng, hexes("b8322a", "d94a3a"), hexes("f4efe6")[0], False)


def glowing_mushroom(rng):
    img, glow = _mushroom(rng, hexes("2b7fd6", "56c8f0"), hexes("d8fbff")[0], True)
    return img, glow


CACTUS = hexes("2f6b2a", "3a7f32", "47933a", "58a847")


def cactus_side(rng):
    # columns 0 and 15 are transparent: the hash planes sit 1/16 inside the cell
    v = 0.55 * np.tile((np.arange(N) % 4 == 1)[None, :], (N, 1)) + 0.45 * fbm(rng)
    rgb = ramp(v, CACTUS)
    spines = (rng.random((N, N)) < 0.06) & ((_xx % 4) == 1)
    rgb[spines] = hexes("e8e2b0")[0]
    a = np.full((N, N), 255, np.uint8)
    a[:, [0, N - 1]] = 0
    return rgba(rgb, a), no_glow()


def cactus_top(rng):
    c = (N - 1) / 2
    d = np.maximum(np.abs(_xx - c), np.abs(_yy - c))
    rgb = ramp(0.6 * (d < 3) + 0.3 * ((d.astype(int) % 3) == 0) + 0.1 * fbm(rng), CACTUS)
    a = np.where(d > 6.6, 0, 255).astype(np.uint8)
    return rgba(rgb, a), no_glow()


# ---------------------------------------------------------------- glass, water, lamps

def glass(rng):
    rgb = np.tile(hexes("d8f0f8")[0], (N, N, 1))
    a = np.full((N, N), 28, np.uint8)
    edge = np.minimum(np.minimum(_xx, _yy), np.minimum(N - 1 - _xx, N - 1 - _yy)) == 0
    rgb[edge] = hexes("b5d3dc")[0]
    a[edge] = 230
    for k, (y0, x0) in enumerate(((3, 3), (9, 5))):  # two diagonal glints
        for i in range(4 - k):
            y, x = y0 + i, x0 + 3 - k - i
            rgb[y, x] = hexes("ffffff")[0]
            a[y, x] = 150
    return rgba(rgb, a), no_glow()


WATER = hexes("1d4f9a", "2459ab", "2c66bb", "3673c8", "4a86d4")


def water(rng):
    v = fbm(rng, amps=(0.4, 0.35, 0.15, 0.1))
    # horizontal wave streaks
    v = 0.7 * v + 0.3 * (0.5 + 0.5 * np.sin((_yy + 3 * noise(rng, 2)) * np.pi / 4))
    rgb = ramp(v, WATER)
    a = np.full((N, N), 170, np.uint8)
    crest = v > 0.85
    rgb[crest] = hexes("7fb2e8")[0]
    a[crest] = 190
    return rgba(rgb, a), no_glow()


def _lamp(colour: str):
    def paint(rng):
        base = hexes(colour)[0]
        frame = hexes("3a3a40", "4d4d55")
        d = np.minimum(np.minimum(_xx, _yy), np.minimum(N - 1 - _xx, N - 1 - _yy))
        v = fbm(rng)
        # panel: light near the centre, subtle pixel variation, never dim
        c = (N - 1) / 2
        r = np.hypot(_xx - c, _yy - c) / c
        lum = np.clip(1.05 - 0.35 * r + 0.12 * (v - 0.5), 0.55, 1.1)
        rgb = base[None, None, :] * lum[..., None]
        rgb = np.minimum(rgb + 90 * np.clip(0.6 - r, 0, 1)[..., None], 255)  # hot core
        glow = np.full((N, N), 255, np.uint8)
        cross = ((_xx == 7) | (_xx == 8) | (_yy == 7) | (_yy == 8)) & (d >= 2)
        rgb[cross] = np.minimum(base * 0.8 + 40, 255)  # faint window bars
        glow[cross] = 200
        rgb[d < 2] = frame[(d[d < 2] + (_xx[d < 2] + _yy[d < 2]) % 2) % 2]
        glow[d < 2] = 0
        return rgba(rgb), glow
    paint.__name__ = "lamp"
    return paint


PAINTERS = {
    "stone": stone, "dirt": dirt, "grass_top": grass_top, "grass_side": grass_side,
    "snow": snow, "snow_side": snow_side, "sand": sand, "ore": ore,
    "log_side": log_side, "log_top": log_top, "leaves": leaves, "flowers": flowers,
    "tall_grass": tall_grass, "wheat": wheat, "mushroom": mushroom,
    "glowing_mushroom": glowing_mushroom, "cactus_side": cactus_side,
    "cactus_top": cactus_top, "glass": glass, "water": water,
    "lamp_red": _lamp("ff3a2e"), "lamp_green": _lamp("3cf05a"), "lamp_blue": _lamp("3a6cff"),
    "lamp_white": _lamp("f4f1e8"), "lamp_yellow": _lamp("ffc933"),
}


def fallback(rng, name: str):
    """A texture for a name nobody painted yet: stone-like noise in a hashed colour."""
    h = np.frombuffer(name.encode().ljust(3, b"_")[:3], np.uint8).astype(np.float32)
    tint = 80 + (h * 37 % 150)
    return rgba(tint[None, None, :] * (0.7 + 0.3 * fbm(rng))[..., None]), no_glow()
