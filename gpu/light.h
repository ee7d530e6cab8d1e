// Cellular light helpers (voxel_addon/light/model.py has the model's definition).
// Lanes: one uchar4 per voxel = (R, G, B, D), each 0..15.
#ifndef LIGHT_H
#define LIGHT_H

#define LIGHT_MAX 15
#define LIGHT_OPAQUE_COST 255

// Packed SPEC §3 form: bits 0-3 R, 4-7 G, 8-11 B, 12-15 D.
inline ushort light_pack(uchar4 v) {
    return (ushort)(v.x | (v.y << 4) | (v.z << 8) | (v.w << 12));
}

// One relaxation step of voxel i (padded index): max over 6 neighbours minus the cost
// of entering this voxel, saturating; OPAQUE_COST makes opaque voxels keep their value.
inline uchar4 light_step(global const uchar4* L, int i, int sy, int sz, uchar c) {
    uchar4 m = max(max(max(L[i - 1], L[i + 1]), max(L[i - sy], L[i + sy])),
                   max(L[i - sz], L[i + sz]));
    return max(L[i], sub_sat(m, (uchar4)(c)));
}

#endif
