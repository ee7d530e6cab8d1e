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

// ---- generated passes ----
