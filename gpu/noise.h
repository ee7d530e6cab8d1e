// Noise (SPEC F4, thesis §2.1): Perlin 2D/3D (Perlin 2002), Voronoi/Worley 2D/3D.
//
// The NumPy twin is voxel_addon/generation/noise.py. Both do the same IEEE float32
// operations in the same order, so results are bit-identical, not just close: the
// generator thresholds these values into block ids and a flipped threshold would
// make the backends disagree. Hence: FP_CONTRACT OFF (no a*b+c fused into fma),
// only + - * / sqrt floor min max (no pow/exp/sin, whose rounding is not pinned),
// integer hashes for everything random. Build without -cl-fast-relaxed-math and
// -cl-mad-enable, with -cl-fp32-correctly-rounded-divide-sqrt.
//
// Speed on pocl (CPU): pocl runs a work-group as a loop over work-items and lets
// LLVM's loop vectorizer turn it into SIMD over adjacent work-items. That only
// happens when the loop body has no calls and no control flow that cannot become
// selects. C99 `inline` is a hint LLVM ignores for big functions (perlin3 is just
// over its cost threshold), so every helper is VX_INLINE (always_inline), loops
// are unrolled and branches are written as selects: ~5x faster than without.
#ifndef VOXEL_NOISE_H
#define VOXEL_NOISE_H
#pragma OPENCL FP_CONTRACT OFF
#define VX_INLINE __attribute__((always_inline)) inline

// lowbias32 (C. Wellons): a cheap full-avalanche 32-bit mix.
VX_INLINE uint vx_mix(uint h) {
    h ^= h >> 16; h *= 0x7feb352du;
    h ^= h >> 15; h *= 0x846ca68bu;
    h ^= h >> 16;
    return h;
}

// Seed of noise instance `salt` in a world with seed `seed` (same on the host).
VX_INLINE uint vx_inst(uint seed, uint salt) { return vx_mix(seed ^ (salt * 0x9E3779B9u)); }

VX_INLINE uint vx_hash2(int x, int y, uint s) {
    return vx_mix((uint)x * 0x8da6b343u + (uint)y * 0xd8163841u + s);
}
VX_INLINE uint vx_hash3(int x, int y, int z, uint s) {
    return vx_mix((uint)x * 0x8da6b343u + (uint)y * 0xd8163841u + (uint)z * 0xcb1ab31fu + s);
}
// Top 24 bits as a float in [0, 1): exact in float32.
VX_INLINE float vx_unit(uint h) { return (float)(h >> 8) * 0x1p-24f; }
VX_INLINE uint vx_next(uint h) { return vx_mix(h + 0x68e31da4u); }

VX_INLINE float vx_fade(float t) { return t * t * t * (t * (t * 6.0f - 15.0f) + 10.0f); }
VX_INLINE float vx_lerp(float t, float a, float b) { return a + t * (b - a); }

// Perlin 2002's 12 cube-edge gradients (16 entries, 4 repeated).
VX_INLINE float vx_grad3(int h, float x, float y, float z) {
    h &= 15;
    float u = h < 8 ? x : y;
    float v = h < 4 ? y : (h == 12 || h == 14 ? x : z);
    return ((h & 1) ? -u : u) + ((h & 2) ? -v : v);
}
// 2D: four axis and four diagonal unit gradients.
VX_INLINE float vx_grad2(int h, float x, float y) {
    float a = (h & 1) ? -x : x;
    float b = (h & 1) ? -y : y;
    float c = (h & 2) ? -y : y;
    return (h & 4) ? (a + c) * 0x1.6a09e6p-1f : ((h & 2) ? b : a);
}

// min and sqrt without pocl's library calls (which the vectorizer cannot widen);
// the NumPy twin writes the same selects (noise.py), so even NaN and -0 agree.
VX_INLINE float vx_fmin(float a, float b) { return b < a ? b : a; }
VX_INLINE float vx_fmax(float a, float b) { return b > a ? b : a; }
VX_INLINE float vx_sqrt(float a) { return __builtin_sqrtf(a); }  // IEEE, correctly rounded

// floor as int by a cast and a compare: vectorizes to a few SIMD ops. Equals
// (int)floor(v) wherever that is defined (|v| < 2^31).
VX_INLINE int vx_ifloor(float v) { int i = (int)v; return i - (v < (float)i ? 1 : 0); }

// perm: 512 ints, a seeded permutation of 0..255 repeated twice. Each noise
// instance shifts the lattice by its own offsets so instances are independent.
VX_INLINE float perlin2(float x, float y, __constant const int* perm, uint s) {
    int ix = vx_ifloor(x), iy = vx_ifloor(y);
    int X = (ix + (int)(s & 255u)) & 255;
    int Y = (iy + (int)((s >> 8) & 255u)) & 255;
    x = x - (float)ix; y = y - (float)iy;
    float u = vx_fade(x), v = vx_fade(y);
    int A = perm[X] + Y, B = perm[X + 1] + Y;
    float x1 = x - 1.0f, y1 = y - 1.0f;
    return vx_lerp(v, vx_lerp(u, vx_grad2(perm[A], x, y), vx_grad2(perm[B], x1, y)),
                      vx_lerp(u, vx_grad2(perm[A + 1], x, y1), vx_grad2(perm[B + 1], x1, y1)));
}

VX_INLINE float perlin3(float x, float y, float z, __constant const int* perm, uint s) {
    int ix = vx_ifloor(x), iy = vx_ifloor(y), iz = vx_ifloor(z);
    int X = (ix + (int)(s & 255u)) & 255;
    int Y = (iy + (int)((s >> 8) & 255u)) & 255;
    int Z = (iz + (int)((s >> 16) & 255u)) & 255;
    x = x - (float)ix; y = y - (float)iy; z = z - (float)iz;
    float u = vx_fade(x), v = vx_fade(y), w = vx_fade(z);
    int A = perm[X] + Y, AA = perm[A] + Z, AB = perm[A + 1] + Z;
    int B = perm[X + 1] + Y, BA = perm[B] + Z, BB = perm[B + 1] + Z;
    float x1 = x - 1.0f, y1 = y - 1.0f, z1 = z - 1.0f;
    return vx_lerp(w,
        vx_lerp(v, vx_lerp(u, vx_grad3(perm[AA], x, y, z), vx_grad3(perm[BA], x1, y, z)),
                   vx_lerp(u, vx_grad3(perm[AB], x, y1, z), vx_grad3(perm[BB], x1, y1, z))),
        vx_lerp(v, vx_lerp(u, vx_grad3(perm[AA + 1], x, y, z1), vx_grad3(perm[BA + 1], x1, y, z1)),
                   vx_lerp(u, vx_grad3(perm[AB + 1], x, y1, z1), vx_grad3(perm[BB + 1], x1, y1, z1))));
}

// Voronoi / Worley: one feature point per unit cell, searched in the 3^D cells
// around; returns (F1, F2, value of the nearest point in [0,1)).
// metric 0: Euclidean; 1: the L4 metric of thesis eq. 2.15. Distances are compared
// raised to the metric's power and rooted once at the end. The cell loops are
// unrolled by macros and the updates are selects, so the whole search vectorizes.
#define VX_VORO_UPDATE(d, hv) { int lt = (d) < f1; f2 = lt ? f1 : vx_fmin(f2, (d)); \
    val = lt ? vx_unit(hv) : val; f1 = lt ? (d) : f1; }
#define VX_VORO2_CELL(dx, dy) { \
    uint h = vx_hash2(ix + (dx), iy + (dy), s); float px = vx_unit(h); h = vx_next(h); \
    float py = vx_unit(h); h = vx_next(h); \
    float ex = ((float)(dx) + px) - x, ey = ((float)(dy) + py) - y; \
    float a = ex * ex, b = ey * ey; float d = metric ? a * a + b * b : a + b; \
    VX_VORO_UPDATE(d, h) }
#define VX_VORO2_ROW(dy) VX_VORO2_CELL(-1, dy) VX_VORO2_CELL(0, dy) VX_VORO2_CELL(1, dy)

VX_INLINE float3 voronoi2(float x, float y, int metric, uint s) {
    int ix = vx_ifloor(x), iy = vx_ifloor(y);
    x = x - (float)ix; y = y - (float)iy;
    float f1 = 1e9f, f2 = 1e9f, val = 0.0f;
    VX_VORO2_ROW(-1) VX_VORO2_ROW(0) VX_VORO2_ROW(1)
    if (metric) { f1 = vx_sqrt(vx_sqrt(f1)); f2 = vx_sqrt(vx_sqrt(f2)); }
    else { f1 = vx_sqrt(f1); f2 = vx_sqrt(f2); }
    return (float3)(f1, f2, val);
}

#define VX_VORO3_CELL(dx, dy, dz) { \
    uint h = vx_hash3(ix + (dx), iy + (dy), iz + (dz), s); float px = vx_unit(h); \
    h = vx_next(h); float py = vx_unit(h); h = vx_next(h); float pz = vx_unit(h); \
    h = vx_next(h); \
    float ex = ((float)(dx) + px) - x, ey = ((float)(dy) + py) - y; \
    float ez = ((float)(dz) + pz) - z; \
    float a = ex * ex, b = ey * ey, c = ez * ez; \
    float d = metric ? (a * a + b * b) + c * c : (a + b) + c; \
    VX_VORO_UPDATE(d, h) }
#define VX_VORO3_ROW(dy, dz) VX_VORO3_CELL(-1, dy, dz) VX_VORO3_CELL(0, dy, dz) \
    VX_VORO3_CELL(1, dy, dz)
#define VX_VORO3_LAYER(dz) VX_VORO3_ROW(-1, dz) VX_VORO3_ROW(0, dz) VX_VORO3_ROW(1, dz)

VX_INLINE float3 voronoi3(float x, float y, float z, int metric, uint s) {
    int ix = vx_ifloor(x), iy = vx_ifloor(y), iz = vx_ifloor(z);
    x = x - (float)ix; y = y - (float)iy; z = z - (float)iz;
    float f1 = 1e9f, f2 = 1e9f, val = 0.0f;
    VX_VORO3_LAYER(-1) VX_VORO3_LAYER(0) VX_VORO3_LAYER(1)
    if (metric) { f1 = vx_sqrt(vx_sqrt(f1)); f2 = vx_sqrt(vx_sqrt(f2)); }
    else { f1 = vx_sqrt(f1); f2 = vx_sqrt(f2); }
    return (float3)(f1, f2, val);
}

#endif
