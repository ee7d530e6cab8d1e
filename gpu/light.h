// Cellular light helpers (voxel_addon/light/model.py has the model's definition).
// Lanes: 4 bytes per voxel = (R, G, B, D), each 0..15. Kernels work on 4 adjacent
// x voxels at once as one uchar16 (explicit SIMD; pocl does not vectorize the
// divergent per-column loops by itself).
#ifndef LIGHT_H
#define LIGHT_H

#define LIGHT_MAX 15
#define LIGHT_OPAQUE_COST 255

// Packed SPEC §3 form: bits 0-3 R, 4-7 G, 8-11 B, 12-15 D.
inline ushort light_pack(uchar4 v) {
    return (ushort)(v.x | (v.y << 4) | (v.z << 8) | (v.w << 12));
}

// Relax 4 voxels (lanes at byte offset 4*i) in place; sx/sz are the y and z strides
// in voxels. Cost 255 (opaque, or padding) keeps a voxel unchanged. Returns 1 if
// anything changed.
inline int light_step4(global uchar* L, global const uchar* cost, int i, int sy, int sz) {
    uchar16 v = vload16(0, L + 4 * i);
    uchar16 m = max(max(vload16(0, L + 4 * (i - 1)), vload16(0, L + 4 * (i + 1))),
                    max(vload16(0, L + 4 * (i - sy)), vload16(0, L + 4 * (i + sy))));
    m = max(m, max(vload16(0, L + 4 * (i - sz)), vload16(0, L + 4 * (i + sz))));
    uchar4 c = vload4(0, cost + i);
    uchar16 c16 = shuffle(c, (uchar16)(0, 0, 0, 0, 1, 1, 1, 1, 2, 2, 2, 2, 3, 3, 3, 3));
    uchar16 n = max(v, sub_sat(m, c16));
    vstore16(n, 0, L + 4 * i);
    return any(n != v);
}

#endif
