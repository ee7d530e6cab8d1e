// Full light solve of a (W, H, Z) block slab with open sky above it and dark air around.
// Blocks are unpadded (x + W*(y + H*z)). Lanes L (4 bytes/voxel) and cost (1 byte)
// live in a padded grid: x in [-4, SX-4), y in [-1, H+1), z in [-1, Z+1); padding
// has lanes 0 and cost 255, i.e. it is the model's dark air outside that never
// changes. Work-items own groups of 4 adjacent columns (g, y), x = 4g..4g+3.
// Host (voxel_addon/light/cl.py): light_start once, then light_relax passes until
// none changes anything, then light_pack_out.
#include "light.h"

#define IDX(x, y, z) (((x) + 4) + SX * (((y) + 1) + (H + 2) * ((z) + 1)))

// Steps 1-2: emission and the daylight column pass; per column for the host:
// lowest non-opaque z, 1 + highest non-opaque z with D < 15, top emitter z.
kernel void light_start(global const ushort* blocks, global const uchar* opaque,
                        global const uchar* att, global const uchar4* emis,
                        global uchar* cost, global uchar4* L, global int4* info,
                        int W, int H, int Z, int SX) {
    int x = get_global_id(0), y = get_global_id(1);
    uchar carry = LIGHT_MAX;
    int lo = Z, hi = 0, em = -1;
    for (int z = Z - 1; z >= 0; z--) {
        ushort b = blocks[x + W * (y + H * z)];
        uchar op = opaque[b], a = att[b];
        carry = op ? (uchar)0 : sub_sat(carry, a);
        int i = IDX(x, y, z);
        cost[i] = op ? (uchar)LIGHT_OPAQUE_COST : (uchar)(1 + a);
        uchar4 e = emis[b];
        if (!op) lo = z;
        if (!op && carry < LIGHT_MAX && hi == 0) hi = z + 1;
        if (em < 0 && (e.x | e.y | e.z)) em = z;
        e.w = carry;
        L[i] = e;
    }
    info[x + W * y] = (int4)(lo, hi, em, 0);
}

// Step 3, one in-place pass. Group (g, y) relaxes z in range[g + G*y] = [lo, hi)
// (outside it nothing can change), sweeping up then down so vertical propagation
// completes within a pass; it is skipped unless a group in its 3x3 neighbourhood
// changed in the previous pass (prev). Reading neighbours mid-update is safe:
// values only grow, never beyond the fixpoint.
kernel void light_relax(global uchar* L, global const uchar* cost, global const int2* range,
                        global const uchar* prev, global uchar* cur, global int* any_change,
                        int W, int H, int Z, int SX) {
    int g = get_global_id(0), y = get_global_id(1), G = get_global_size(0);
    int act = 0;
    for (int dy = -1; dy <= 1; dy++)
        for (int dg = -1; dg <= 1; dg++) {
            int gg = g + dg, yy = y + dy;
            if (gg >= 0 && gg < G && yy >= 0 && yy < H) act |= prev[gg + G * yy];
        }
    int2 r = range[g + G * y];
    uchar ch = 0;
    if (act && r.x < r.y) {
        int sy = SX, sz = SX * (H + 2);
        int i = IDX(4 * g, y, r.x);
        for (int z = r.x; z < r.y; z++, i += sz) ch |= light_step4(L, cost, i, sy, sz);
        for (int z = r.y - 1; z >= r.x; z--) { i -= sz; ch |= light_step4(L, cost, i, sy, sz); }
    }
    cur[g + G * y] = ch;
    if (ch) any_change[0] = 1;
}

kernel void light_pack_out(global const uchar4* L, global ushort* out, int W, int H, int Z,
                           int SX) {
    int x = get_global_id(0), y = get_global_id(1);
    for (int z = 0; z < Z; z++) out[x + W * (y + H * z)] = light_pack(L[IDX(x, y, z)]);
}
