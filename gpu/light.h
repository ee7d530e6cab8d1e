// Cellular light helpers (voxel_addon/light/model.py has the model's definition).
// Lanes: 4 bytes per voxel = (R, G, B, D), each 0..15. Kernels work on 4 adjacent
// x voxels at once as one uchar16 (explicit SIMD; pocl does not vectorize the
// divergent per-line loops by itself).
#ifndef LIGHT_H
#define LIGHT_H

#define LIGHT_MAX 15
#define LIGHT_OPAQUE_COST 255

// Packed SPEC §3 form: bits 0-3 R, 4-7 G, 8-11 B, 12-15 D.
inline ushort light_pack(uchar4 v) {
    return (ushort)(v.x | (v.y << 4) | (v.z << 8) | (v.w << 12));
}

inline ushort4 light_pack4(uchar16 v) {
    return (ushort4)(light_pack(v.s0123), light_pack(v.s4567), light_pack(v.s89ab),
                     light_pack(v.scdef));
}

inline uchar16 light_cost16(uchar4 c) {
    return shuffle(c, (uchar16)(0, 0, 0, 0, 1, 1, 1, 1, 2, 2, 2, 2, 3, 3, 3, 3));
}

// One step of a line sweep for 4 voxels side by side: each takes
// max(own, from - cost) per component; cost 255 (opaque, padding) keeps it unchanged.
inline uchar16 light_spread4(uchar16 v, uchar16 from, uchar4 c) {
    return max(v, sub_sat(from, light_cost16(c)));
}

// 1 if any of the 4 voxels v could raise its neighbour n (lanes n, costs c).
inline int light_raises4(uchar16 v, uchar16 n, uchar4 c) {
    return any(sub_sat(v, light_cost16(c)) > n);
}

#endif
