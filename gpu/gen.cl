// Generator programs: generation/cl_exec.py appends one kernel per pass (unit),
// compiled from a generation/lang.py Program. This file holds what they share.
#include "noise.h"
#include "noise8.h"

// Floor division and modulo by a positive constant (NumPy's // and %).
VX_INLINE int vx_fdiv(int a, int n) { return (a - (a < 0 ? n - 1 : 0)) / n; }
VX_INLINE int vx_fmod(int a, int n) { return a - vx_fdiv(a, n) * n; }
VX_INLINE int vx_iabs(int a) { return a < 0 ? -a : a; }
VX_INLINE int vx_imin(int a, int b) { return b < a ? b : a; }
VX_INLINE int vx_imax(int a, int b) { return b > a ? b : a; }
VX_INLINE float vx_floor(float a) { return __builtin_floorf(a); }
VX_INLINE float vx_fabs(float a) { return __builtin_fabsf(a); }

// prev(dz) of a 3D pass: the previous pass's block at layer z of chunk c, 0 outside
// 0..255. The load is clamped into range and masked, not branched around, so the
// work-group loop still vectorizes.
VX_INLINE int vx_prev(__global const ushort* p, int c, int z, int lid) {
    int v = (int)p[c * 65536 + vx_imin(vx_imax(z, 0), 255) * 256 + lid];
    return ((z >= 0) & (z < 256)) ? v : 0;
}

// The big noise functions once more, never inlined (`_c`, "called"): a kernel that calls
// one of them many times (clsource.source: more than CALLS_INLINED) calls these
// instead. Inlined, every call is a copy of its body, and pocl compiles a kernel's
// work-group code with LLVM at its first launch: version 2's surface-caves kernel (24
// perlin3_8) took ~5 s of a fresh install's ~6 s there, the biomes' 26 perlin2 ~2 s;
// called, 0.3 s and 0.7 s (issue 28). The values are the same (the same function,
// FP_CONTRACT OFF); such a kernel gives up pocl's work-group vectorizer, which these
// big 2D kernels hardly got (the far surface's batch: within the noise).
#define VX_CALLED __attribute__((noinline))
VX_CALLED float perlin2_c(float x, float y, __constant const int* perm, uint s) {
    return perlin2(x, y, perm, s);
}
VX_CALLED float perlin3_c(float x, float y, float z, __constant const int* perm, uint s) {
    return perlin3(x, y, z, perm, s);
}
VX_CALLED float3 voronoi2_c(float x, float y, int metric, uint s) {
    return voronoi2(x, y, metric, s);
}
VX_CALLED float3 voronoi3_c(float x, float y, float z, int metric, uint s) {
    return voronoi3(x, y, z, metric, s);
}
VX_CALLED vf8 perlin2_8_c(vf8 x, vf8 y, __constant const int* perm, uint s) {
    return perlin2_8(x, y, perm, s);
}
VX_CALLED vf8 perlin3_8_c(vf8 x, vf8 y, vf8 z, __constant const int* perm, uint s) {
    return perlin3_8(x, y, z, perm, s);
}
VX_CALLED vf8x3 voronoi2_8_c(vf8 x, vf8 y, int metric, uint s) {
    return voronoi2_8(x, y, metric, s);
}

// ---- generated passes ----
