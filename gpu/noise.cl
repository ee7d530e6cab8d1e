// Noise sampled at given points: the OpenCL side of the noise tests and bench.
// kind: 0 perlin2, 1 perlin3, 2 voronoi2, 3 voronoi3 (F1, F2, value -> out[3*i..]).
#include "noise.h"

__kernel void sample(__global const float* xyz, __global float* out, __constant const int* perm,
                     uint s, int kind, int metric, int n) {
    int i = get_global_id(0);
    if (i >= n) return;
    float x = xyz[3 * i], y = xyz[3 * i + 1], z = xyz[3 * i + 2];
    if (kind == 0) out[i] = perlin2(x, y, perm, s);
    else if (kind == 1) out[i] = perlin3(x, y, z, perm, s);
    else {
        float3 v = kind == 2 ? voronoi2(x, y, metric, s) : voronoi3(x, y, z, metric, s);
        out[3 * i] = v.x; out[3 * i + 1] = v.y; out[3 * i + 2] = v.z;
    }
}

// A 4-octave 3D Perlin over a grid, for the bench (throughput, not correctness).
// Octaves unrolled: a loop around an inlined perlin3 keeps pocl from vectorizing.
__kernel void fbm3_grid(__global float* out, __constant const int* perm, uint seed, float scale) {
    int x = get_global_id(0), y = get_global_id(1), z = get_global_id(2);
    float fx = (float)x * scale, fy = (float)y * scale, fz = (float)z * scale;
    float sum = perlin3(fx, fy, fz, perm, vx_inst(seed, 0u));
    sum = sum + perlin3(fx * 2.0f, fy * 2.0f, fz * 2.0f, perm, vx_inst(seed, 1u)) * 0.5f;
    sum = sum + perlin3(fx * 4.0f, fy * 4.0f, fz * 4.0f, perm, vx_inst(seed, 2u)) * 0.25f;
    sum = sum + perlin3(fx * 8.0f, fy * 8.0f, fz * 8.0f, perm, vx_inst(seed, 3u)) * 0.125f;
    out[x + get_global_size(0) * (y + get_global_size(1) * z)] = sum;
}
