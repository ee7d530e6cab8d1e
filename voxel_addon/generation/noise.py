"""Noise in NumPy (SPEC F4, thesis §2.1): the reference twin of gpu/noise.h.

Every function does the same float32 operations in the same order as the C code,
so the two agree bit for bit (tests check it): generators threshold these values
into block ids. Inputs broadcast; outputs are float32. `perm` is a seeded
permutation table (see `perm_table`), `s` a noise instance seed (`inst`).
"""
from __future__ import annotations

import numpy as np

M32 = 0xFFFFFFFF
F = np.float32
U = np.uint32


def mix(h):
    """lowbias32 on a uint32 array."""
    h = h ^ (h >> U(16))
    h = h * U(0x7feb352d)
    h = h ^ (h >> U(15))
    h = h * U(0x846ca68b)
    return h ^ (h >> U(16))


def mix_int(h: int) -> int:
    """lowbias32 on a Python int (host-side seeds)."""
    h &= M32
    h ^= h >> 16
    h = (h * 0x7feb352d) & M32
    h ^= h >> 15
    h = (h * 0x846ca68b) & M32
    return h ^ (h >> 16)


def seed32(seed: int) -> int:
    """Any integer seed -> the uint32 the kernels use."""
    seed = int(seed)
    h = 0x2545F491
    while True:  # fold 32 bits at a time so big (and negative) seeds stay distinct
        h = mix_int(h ^ (seed & M32))
        seed >>= 32
        if seed in (0, -1):
            return mix_int(h ^ (seed & M32))


def inst(seed: int, salt: int) -> int:
    """Seed of noise instance `salt` (vx_inst in noise.h)."""
    return mix_int(seed ^ ((salt * 0x9E3779B9) & M32))


def perm_table(seed: int) -> np.ndarray:
    """Perlin's permutation of 0..255, shuffled from the seed, repeated twice (512 int32)."""
    p = list(range(256))
    h = mix_int(seed ^ 0x5bd1e995)
    for i in range(255, 0, -1):  # Fisher-Yates with a deterministic integer stream
        h = mix_int(h + 0x68e31da4)
        j = h % (i + 1)
        p[i], p[j] = p[j], p[i]
    return np.array(p + p, np.int32)


def _u(a):
    """int32 -> uint32 with two's complement wrap (as C's (uint) cast)."""
    return np.asarray(a, np.int32).view(np.uint32) if np.ndim(a) else U(np.int64(a) & M32)


def hash2(x, y, s: int):
    return mix(_u(x) * U(0x8da6b343) + _u(y) * U(0xd8163841) + U(s))


def hash3(x, y, z, s: int):
    return mix(_u(x) * U(0x8da6b343) + _u(y) * U(0xd8163841) + _u(z) * U(0xcb1ab31f) + U(s))


def unit(h):
    """Top 24 bits as float32 in [0, 1)."""
    return (h >> U(8)).astype(F) * F(2.0 ** -24)


def nxt(h):
    return mix(h + U(0x68e31da4))


def fade(t):
    return t * t * t * (t * (t * F(6) - F(15)) + F(10))


def lerp(t, a, b):
    return a + t * (b - a)


def grad3(h, x, y, z):
    """h in 0..15 (perm & 15). Negation is a flip of the sign bit, done as an integer xor
    (same bits as -u, about twice as fast as np.where on both signs)."""
    u = np.where(h < 8, x, y).view(np.int32)
    v = np.where(h < 4, y, np.where((h & 13) == 12, x, z)).view(np.int32)
    s = h << 31
    u ^= s
    s = h & 2
    s <<= 30
    v ^= s
    u = u.view(F)
    u += v.view(F)
    return u


_G3 = []  # grad3's 16 gradients as float32 (x, y, z) coefficients, made on first use


def _grads3(perm):
    """Per perm index: the gradient of perm[i] & 15 as coefficient tables gx, gy, gz
    (each 1, -1 or +0, derived from grad3 itself), and perm & 15."""
    if not _G3:
        one, zero = F(1), F(0)
        g = np.array([[grad3(np.int32(h), *(one if a == b else zero for b in range(3)))
                       for a in range(3)] for h in range(16)], F)
        _G3.append(np.where(g == 0, zero, g))
    g = np.zeros((len(perm), 4), F)
    g[:, :3] = _G3[0][perm & 15]
    # one 16-byte gather per lookup instead of three 4-byte ones: rows as complex128
    return g.view(np.complex128).ravel(), perm & 15


def _dot3(tab, i, x, y, z):
    """grad3(perm[i] & 15, x, y, z) as gx*x + gy*y + gz*z: 4x fewer array passes than
    the selects, and the same value except that an exact zero may have the other sign
    (multiplying by +-1 is exact; adding a zero to a nonzero number changes nothing)."""
    rows, h = tab
    if np.ndim(i) == 0:
        return grad3(h[i], x, y, z)
    g = rows.take(i).view(F).reshape(np.shape(i) + (4,))  # take: faster than g[i]
    r = g[..., 0] * x
    r += g[..., 1] * y
    r += g[..., 2] * z
    return r


def _sel3(tab, i, x, y, z):
    return grad3(tab[1].take(i), x, y, z)


_G2 = []  # grad2's 8 gradients: coefficients (x, y) and the diagonal factor


def _dot2(perm, i, x, y):
    """grad2(perm[i], x, y) as (gx*x + gy*y) * k, equal up to the sign of a zero (_dot3)."""
    if not _G2:
        one, zero = F(1), F(0)
        g = np.array([[grad2(np.int32(h), one if a == 0 else zero, one if a == 1 else zero)
                       for a in range(2)] for h in range(8)], F)
        k = np.where(np.arange(8) & 4, F(float.fromhex("0x1.6a09e6p-1")), one).astype(F)
        g = np.sign(np.where(g == 0, zero, g)).astype(F)  # diagonals: g = +-k
        rows = np.zeros((8, 4), F)
        rows[:, 0], rows[:, 1], rows[:, 2] = g[:, 0], g[:, 1], k
        _G2.append(rows.view(np.complex128).ravel())
    if np.ndim(i) == 0:
        return grad2(perm[i], x, y)
    g = _G2[0].take(perm.take(i) & 7).view(F).reshape(np.shape(i) + (4,))
    r = g[..., 0] * x
    r += g[..., 1] * y
    r *= g[..., 2]
    return r


def _sel2(perm, i, x, y):
    return grad2(perm.take(i), x, y)


def _exact(fast, slow, coords, *args):
    """fast(*coords, *args), whose gradients (_dot2/_dot3) may give a zero the other sign:
    such a difference only ever yields a zero (x + 0 = x, x * 0 = 0), so the results
    that are exactly zero (lattice planes, a few) are recomputed with the selects."""
    if all(np.ndim(c) == 0 for c in coords):
        return slow(*coords, *args)
    r = fast(*coords, *args)
    zero = r == 0
    if zero.any():
        r[zero] = slow(*(np.broadcast_to(np.asarray(c, F), r.shape)[zero] for c in coords), *args)
    return r


def _lerp_(t, a, b):
    """lerp(t, a, b) reusing the new array b - a (b is a temporary of the caller)."""
    d = b - a
    d *= t
    d += a
    return d


def grad2(h, x, y):
    a = np.where(h & 1, -x, x)
    b = np.where(h & 1, -y, y)
    c = np.where(h & 2, -y, y)
    return np.where(h & 4, (a + c) * F(float.fromhex("0x1.6a09e6p-1")), np.where(h & 2, b, a))


def _lattice(v, shift: int):
    v = np.asarray(v, F)
    fv = np.floor(v) + F(0)  # + 0 turns floor(-0.0) into +0.0, as (float)vx_ifloor does
    return (fv.astype(np.int32) + np.int32(shift)) & 255, v - fv


def perlin2(x, y, perm, s: int):
    return _exact(_perlin2, _perlin2_sel, (x, y), perm, s)


def _perlin2_sel(x, y, perm, s):
    return _perlin2(x, y, perm, s, _sel2)


def _perlin2(x, y, perm, s, dot=_dot2):
    X, x = _lattice(x, s & 255)
    Y, y = _lattice(y, (s >> 8) & 255)
    u, v = fade(x), fade(y)
    P = perm.take
    A = P(X) + Y
    B = P(X + 1) + Y
    x1, y1 = x - F(1), y - F(1)
    L, d = _lerp_, dot
    return L(v, L(u, d(perm, A, x, y), d(perm, B, x1, y)),
             L(u, d(perm, A + 1, x, y1), d(perm, B + 1, x1, y1)))


def perlin3(x, y, z, perm, s: int):
    return _exact(_perlin3, _perlin3_sel, (x, y, z), perm, s)


def _perlin3_sel(x, y, z, perm, s):
    return _perlin3(x, y, z, perm, s, _sel3)


def _perlin3(x, y, z, perm, s, dot=_dot3):
    X, x = _lattice(x, s & 255)
    Y, y = _lattice(y, (s >> 8) & 255)
    Z, z = _lattice(z, (s >> 16) & 255)
    u, v, w = fade(x), fade(y), fade(z)
    g, g1 = _grads3(perm), _grads3(np.roll(perm, -1))  # g1 at i: g at i + 1
    P = perm.take
    A = P(X) + Y
    AA, AB = P(A) + Z, P(A + 1) + Z
    B = P(X + 1) + Y
    BA, BB = P(B) + Z, P(B + 1) + Z
    x1, y1, z1 = x - F(1), y - F(1), z - F(1)
    L, d = _lerp_, dot
    return L(w,
             L(v, L(u, d(g, AA, x, y, z), d(g, BA, x1, y, z)),
               L(u, d(g, AB, x, y1, z), d(g, BB, x1, y1, z))),
             L(v, L(u, d(g1, AA, x, y, z1), d(g1, BA, x1, y, z1)),
               L(u, d(g1, AB, x, y1, z1), d(g1, BB, x1, y1, z1))))


def octaves(fn, coords, perm, seed: int, salt: int, n: int = 4, lacunarity: float = 2.0,
            gain: float = 0.5):
    """Thesis eq. 2.10: sum over octaves o of fn(pos * lacunarity^o) * gain^o.

    Octave o uses instance inst(seed, salt + o). Same order as the pass language's
    `octaves`, so a generator can mix the two.
    """
    total = None
    for o in range(n):
        f, a = F(lacunarity ** o), F(gain ** o)
        v = fn(*[np.asarray(c, F) * f for c in coords], perm, inst(seed, salt + o)) * a
        total = v if total is None else total + v
    return total


def _metric_root(d, metric: int):
    return np.sqrt(np.sqrt(d)) if metric else np.sqrt(d)


def voronoi2(x, y, s: int, metric: int = 0):
    """(F1, F2, value) of a 2D Voronoi diagram with one feature point per unit cell."""
    x, y = np.asarray(x, F), np.asarray(y, F)
    fx, fy = np.floor(x), np.floor(y)
    ix, iy = fx.astype(np.int32), fy.astype(np.int32)
    x, y = x - (fx + F(0)), y - (fy + F(0))  # as vx_ifloor: -0.0 -> +0.0
    shape = np.broadcast(x, y).shape
    f1 = np.full(shape, F(1e9))
    f2 = f1.copy()
    val = np.zeros(shape, F)
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            h = hash2(ix + np.int32(dx), iy + np.int32(dy), s)
            px = unit(h)
            h = nxt(h)
            py = unit(h)
            h = nxt(h)
            ex, ey = (F(dx) + px) - x, (F(dy) + py) - y
            a, b = ex * ex, ey * ey
            d = a * a + b * b if metric else a + b
            lt = d < f1
            f2 = np.where(lt, f1, np.where(d < f2, d, f2))  # vx_fmin
            val = np.where(lt, unit(h), val)
            f1 = np.where(lt, d, f1)
    return _metric_root(f1, metric), _metric_root(f2, metric), val


def voronoi3(x, y, z, s: int, metric: int = 0):
    """(F1, F2, value) of a 3D Voronoi diagram with one feature point per unit cell."""
    x, y, z = np.asarray(x, F), np.asarray(y, F), np.asarray(z, F)
    fx, fy, fz = np.floor(x), np.floor(y), np.floor(z)
    ix, iy, iz = fx.astype(np.int32), fy.astype(np.int32), fz.astype(np.int32)
    x, y, z = x - (fx + F(0)), y - (fy + F(0)), z - (fz + F(0))
    shape = np.broadcast(x, y, z).shape
    f1 = np.full(shape, F(1e9))
    f2 = f1.copy()
    val = np.zeros(shape, F)
    for dz in (-1, 0, 1):
        for dy in (-1, 0, 1):
            for dx in (-1, 0, 1):
                h = hash3(ix + np.int32(dx), iy + np.int32(dy), iz + np.int32(dz), s)
                px = unit(h)
                h = nxt(h)
                py = unit(h)
                h = nxt(h)
                pz = unit(h)
                h = nxt(h)
                ex, ey, ez = (F(dx) + px) - x, (F(dy) + py) - y, (F(dz) + pz) - z
                a, b, c = ex * ex, ey * ey, ez * ez
                d = (a * a + b * b) + c * c if metric else (a + b) + c
                lt = d < f1
                f2 = np.where(lt, f1, np.where(d < f2, d, f2))  # vx_fmin
                val = np.where(lt, unit(h), val)
                f1 = np.where(lt, d, f1)
    return _metric_root(f1, metric), _metric_root(f2, metric), val
