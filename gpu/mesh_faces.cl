// Face keys of a z band [za, za+Z) of the whole window (for the aggregation methods
// that run in NumPy): one work item per voxel, six (W, H, Z) ushort arrays.
#include "mesh.h"

__kernel void faces(__global const ushort *P, __constant uchar *flags,
                    int W, int H, int za, int Z, __global ushort *keys) {
    int x = get_global_id(0), y = get_global_id(1), z = get_global_id(2);
    if (x >= W || y >= H) return;  // launch is padded to whole work groups
    long PW = W + 2, PL = PW * (H + 2);
    long c = (x + 1) + PW * (y + 1) + PL * (za + z);
    size_t n = (size_t)W * H * Z, o = (size_t)x + (size_t)W * ((size_t)y + (size_t)H * z);
    long step[3] = {1, PW, PL};
#pragma unroll
    for (int d = 0; d < 6; d++) {
        long off = (d & 1) ? step[d >> 1] : -step[d >> 1];
        bool edge = (d == 4 && za + z == 0) || (d == 5 && za + z == 255);
        keys[o + d * n] = face_key(P, flags, c, off, edge, d >= 4 ? (F_CUBE | F_CAP) : F_CUBE);
    }
}
