// Eight-lane twins of noise.h for the 3D generator kernels (generation/cl.py): one
// work-item computes a row of 8 voxels with explicit float8/int8 code, so the SIMD
// no longer depends on pocl's work-group vectorizer (which gives up on the big
// kernels, see generation/README.md). Same IEEE operations in the same order as
// the scalar versions; bools are 0/-1 lanes (OpenCL vector comparisons), and a
// select(b, a, c) here is the scalar `c ? a : b`.
#ifndef VOXEL_NOISE8_H
#define VOXEL_NOISE8_H
#include "noise.h"

typedef float8 vf8;
typedef int8 vi8;
typedef uint8 vu8;
#define VX_LANES ((vi8)(0, 1, 2, 3, 4, 5, 6, 7))
// per-lane loads (no gather instruction in OpenCL C)
#define VX_GATHER8(T, p, i) ((T)((p)[(i).s0], (p)[(i).s1], (p)[(i).s2], (p)[(i).s3], \
                                 (p)[(i).s4], (p)[(i).s5], (p)[(i).s6], (p)[(i).s7]))

VX_INLINE vu8 vx_mix8(vu8 h) {
    h ^= h >> 16; h *= 0x7feb352du;
    h ^= h >> 15; h *= 0x846ca68bu;
    h ^= h >> 16;
    return h;
}
VX_INLINE vu8 vx_hash2_8(vi8 x, vi8 y, uint s) {
    return vx_mix8(as_uint8(x) * 0x8da6b343u + as_uint8(y) * 0xd8163841u + s);
}
VX_INLINE vu8 vx_hash3_8(vi8 x, vi8 y, vi8 z, uint s) {
    return vx_mix8(as_uint8(x) * 0x8da6b343u + as_uint8(y) * 0xd8163841u
                   + as_uint8(z) * 0xcb1ab31fu + s);
}
VX_INLINE vf8 vx_unit8(vu8 h) { return convert_float8(h >> 8) * 0x1p-24f; }
VX_INLINE vu8 vx_next8(vu8 h) { return vx_mix8(h + 0x68e31da4u); }

VX_INLINE vi8 vx_ifloor8(vf8 v) { vi8 i = convert_int8(v); return i + (v < convert_float8(i)); }
VX_INLINE vf8 vx_fade8(vf8 t) { return t * t * t * (t * (t * 6.0f - 15.0f) + 10.0f); }
VX_INLINE vf8 vx_lerp8(vf8 t, vf8 a, vf8 b) { return a + t * (b - a); }
VX_INLINE vf8 vx_fmin8(vf8 a, vf8 b) { return select(a, b, b < a); }
VX_INLINE vf8 vx_fmax8(vf8 a, vf8 b) { return select(a, b, b > a); }
VX_INLINE vi8 vx_imin8(vi8 a, vi8 b) { return select(a, b, b < a); }
VX_INLINE vi8 vx_imax8(vi8 a, vi8 b) { return select(a, b, b > a); }
VX_INLINE vi8 vx_iabs8(vi8 a) { return select(a, -a, a < 0); }
VX_INLINE vi8 vx_fdiv8(vi8 a, int n) { return (a - select((vi8)0, (vi8)(n - 1), a < 0)) / n; }
VX_INLINE vi8 vx_fmod8(vi8 a, int n) { return a - vx_fdiv8(a, n) * n; }

VX_INLINE vf8 vx_grad3_8(vi8 h, vf8 x, vf8 y, vf8 z) {
    h &= 15;
    vf8 u = select(y, x, h < 8);
    vf8 v = select(select(z, x, (h == 12) | (h == 14)), y, h < 4);
    return select(u, -u, (h & 1) != 0) + select(v, -v, (h & 2) != 0);
}
VX_INLINE vf8 vx_grad2_8(vi8 h, vf8 x, vf8 y) {
    vf8 a = select(x, -x, (h & 1) != 0);
    vf8 b = select(y, -y, (h & 1) != 0);
    vf8 c = select(y, -y, (h & 2) != 0);
    return select(select(a, b, (h & 2) != 0), (a + c) * 0x1.6a09e6p-1f, (h & 4) != 0);
}

VX_INLINE vf8 perlin2_8(vf8 x, vf8 y, __constant const int* perm, uint s) {
    vi8 ix = vx_ifloor8(x), iy = vx_ifloor8(y);
    vi8 X = (ix + (int)(s & 255u)) & 255;
    vi8 Y = (iy + (int)((s >> 8) & 255u)) & 255;
    x = x - convert_float8(ix); y = y - convert_float8(iy);
    vf8 u = vx_fade8(x), v = vx_fade8(y);
    vi8 A = VX_GATHER8(vi8, perm, X) + Y, B = VX_GATHER8(vi8, perm, X + 1) + Y;
    vf8 x1 = x - 1.0f, y1 = y - 1.0f;
    return vx_lerp8(v,
        vx_lerp8(u, vx_grad2_8(VX_GATHER8(vi8, perm, A), x, y),
                    vx_grad2_8(VX_GATHER8(vi8, perm, B), x1, y)),
        vx_lerp8(u, vx_grad2_8(VX_GATHER8(vi8, perm, A + 1), x, y1),
                    vx_grad2_8(VX_GATHER8(vi8, perm, B + 1), x1, y1)));
}

// voronoi2 (noise.h) 8 lanes at a time, op for op: (F1, F2, value) as three vectors
typedef struct { vf8 x, y, z; } vf8x3;
#define VX_VORO2_CELL8(dx, dy) { \
    vu8 h = vx_hash2_8(ix + (dx), iy + (dy), s); vf8 px = vx_unit8(h); h = vx_next8(h); \
    vf8 py = vx_unit8(h); h = vx_next8(h); \
    vf8 ex = ((float)(dx) + px) - x, ey = ((float)(dy) + py) - y; \
    vf8 a = ex * ex, b = ey * ey; vf8 d = metric ? a * a + b * b : a + b; \
    vi8 lt = d < f1; f2 = select(vx_fmin8(f2, d), f1, lt); \
    val = select(val, vx_unit8(h), lt); f1 = select(f1, d, lt); }
#define VX_VORO2_ROW8(dy) VX_VORO2_CELL8(-1, dy) VX_VORO2_CELL8(0, dy) VX_VORO2_CELL8(1, dy)

VX_INLINE vf8x3 voronoi2_8(vf8 x, vf8 y, int metric, uint s) {
    vi8 ix = vx_ifloor8(x), iy = vx_ifloor8(y);
    x = x - convert_float8(ix); y = y - convert_float8(iy);
    vf8 f1 = (vf8)1e9f, f2 = (vf8)1e9f, val = (vf8)0.0f;
    VX_VORO2_ROW8(-1) VX_VORO2_ROW8(0) VX_VORO2_ROW8(1)
    if (metric) { f1 = sqrt(sqrt(f1)); f2 = sqrt(sqrt(f2)); }
    else { f1 = sqrt(f1); f2 = sqrt(f2); }
    vf8x3 r = {f1, f2, val};
    return r;
}

VX_INLINE vf8 perlin3_8(vf8 x, vf8 y, vf8 z, __constant const int* perm, uint s) {
    vi8 ix = vx_ifloor8(x), iy = vx_ifloor8(y), iz = vx_ifloor8(z);
    vi8 X = (ix + (int)(s & 255u)) & 255;
    vi8 Y = (iy + (int)((s >> 8) & 255u)) & 255;
    vi8 Z = (iz + (int)((s >> 16) & 255u)) & 255;
    x = x - convert_float8(ix); y = y - convert_float8(iy); z = z - convert_float8(iz);
    vf8 u = vx_fade8(x), v = vx_fade8(y), w = vx_fade8(z);
    vi8 A = VX_GATHER8(vi8, perm, X) + Y;
    vi8 AA = VX_GATHER8(vi8, perm, A) + Z, AB = VX_GATHER8(vi8, perm, A + 1) + Z;
    vi8 B = VX_GATHER8(vi8, perm, X + 1) + Y;
    vi8 BA = VX_GATHER8(vi8, perm, B) + Z, BB = VX_GATHER8(vi8, perm, B + 1) + Z;
    vf8 x1 = x - 1.0f, y1 = y - 1.0f, z1 = z - 1.0f;
    return vx_lerp8(w,
        vx_lerp8(v, vx_lerp8(u, vx_grad3_8(VX_GATHER8(vi8, perm, AA), x, y, z),
                                vx_grad3_8(VX_GATHER8(vi8, perm, BA), x1, y, z)),
                    vx_lerp8(u, vx_grad3_8(VX_GATHER8(vi8, perm, AB), x, y1, z),
                                vx_grad3_8(VX_GATHER8(vi8, perm, BB), x1, y1, z))),
        vx_lerp8(v, vx_lerp8(u, vx_grad3_8(VX_GATHER8(vi8, perm, AA + 1), x, y, z1),
                                vx_grad3_8(VX_GATHER8(vi8, perm, BA + 1), x1, y, z1)),
                    vx_lerp8(u, vx_grad3_8(VX_GATHER8(vi8, perm, AB + 1), x, y1, z1),
                                vx_grad3_8(VX_GATHER8(vi8, perm, BB + 1), x1, y1, z1))));
}

// vx_grad3_8 for one h in every lane: the same selects with a scalar condition, and the
// negations as sign-bit xors (the bits of -u)
VX_INLINE vf8 vx_grad3s_8(int h, vf8 x, vf8 y, vf8 z) {
    h &= 15;
    vf8 u = h < 8 ? x : y;
    vf8 v = h < 4 ? y : ((h == 12) | (h == 14)) ? x : z;
    return as_float8(as_uint8(u) ^ (vu8)((uint)(h & 1) << 31))
         + as_float8(as_uint8(v) ^ (vu8)((uint)(h & 2) << 30));
}

// perlin3_8 for a row whose x spans less than one lattice cell and whose y and z are
// the same in every lane (cl.py proves it from the expressions): a lane's cell is
// lane 0's or lane 7's, so each table lookup is two scalar loads and a select
// instead of eight loads, and each gradient is computed for those two h with scalar
// conditions (vx_grad3s_8) and then picked per lane. The values are the same.
VX_INLINE vf8 perlin3_8r(vf8 x, vf8 y, vf8 z, __constant const int* perm, uint s) {
    vi8 ix = vx_ifloor8(x), iy = vx_ifloor8(y), iz = vx_ifloor8(z);
    vi8 X = (ix + (int)(s & 255u)) & 255;
    int Y = (iy.s0 + (int)((s >> 8) & 255u)) & 255;
    int Z = (iz.s0 + (int)((s >> 16) & 255u)) & 255;
    x = x - convert_float8(ix); y = y - convert_float8(iy); z = z - convert_float8(iz);
    vf8 u = vx_fade8(x), v = vx_fade8(y), w = vx_fade8(z);
    int X0 = X.s0, X7 = X.s7;
    vi8 m = X == (vi8)X0;  /* lanes in lane 0's cell */
    int A0 = perm[X0] + Y, A7 = perm[X7] + Y, B0 = perm[X0 + 1] + Y, B7 = perm[X7 + 1] + Y;
    int AA0 = perm[A0] + Z, AA7 = perm[A7] + Z, AB0 = perm[A0 + 1] + Z, AB7 = perm[A7 + 1] + Z;
    int BA0 = perm[B0] + Z, BA7 = perm[B7] + Z, BB0 = perm[B0 + 1] + Z, BB7 = perm[B7 + 1] + Z;
    vf8 x1 = x - 1.0f, y1 = y - 1.0f, z1 = z - 1.0f;
#define VX_BODY vx_lerp8(w, \
        vx_lerp8(v, vx_lerp8(u, VX_GR(AA0, AA7, x, y, z), VX_GR(BA0, BA7, x1, y, z)), \
                    vx_lerp8(u, VX_GR(AB0, AB7, x, y1, z), VX_GR(BB0, BB7, x1, y1, z))), \
        vx_lerp8(v, vx_lerp8(u, VX_GR(AA0 + 1, AA7 + 1, x, y, z1), \
                                VX_GR(BA0 + 1, BA7 + 1, x1, y, z1)), \
                    vx_lerp8(u, VX_GR(AB0 + 1, AB7 + 1, x, y1, z1), \
                                VX_GR(BB0 + 1, BB7 + 1, x1, y1, z1))))
    vf8 r;
    if (X0 == X7) {  /* the whole row in one cell (most rows): one h per corner */
#define VX_GR(i0, i7, gx, gy, gz) vx_grad3s_8(perm[i0], gx, gy, gz)
        r = VX_BODY;
#undef VX_GR
    } else {  /* a corner's gradient for lane 0's h and lane 7's h, picked per lane */
#define VX_GR(i0, i7, gx, gy, gz) \
    select(vx_grad3s_8(perm[i7], gx, gy, gz), vx_grad3s_8(perm[i0], gx, gy, gz), m)
        r = VX_BODY;
#undef VX_GR
    }
#undef VX_BODY
    return r;
}

// prev(dz) for a row of 8: 0 outside 0..255 (z is the same for the whole row)
VX_INLINE vi8 vx_prev8(__global const ushort* p, int c, int z, int row) {
    if (z < 0 || z > 255) return (vi8)0;
    return convert_int8(vload8(0, p + c * 65536 + z * 256 + row));
}
#endif
