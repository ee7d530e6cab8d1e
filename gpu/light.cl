// Full light solve of a (W, H, Z) block slab with open sky above it and dark air around.
// Lanes L live in a zero-padded (W+2, H+2, Z+2) buffer; blocks/cost are unpadded,
// indexed x + W*(y + H*z). Host: light_start, then light_relax until no change
// (at most 14 passes, which is exact: each in-place pass does at least one Jacobi
// step), then light_pack.
#include "light.h"

#define PAD(x, y, z) (((x) + 1) + (W + 2) * (((y) + 1) + (H + 2) * ((z) + 1)))

// Steps 1-2: emission and the daylight column pass. One work-item per column.
kernel void light_start(global const ushort* blocks, global const uchar* opaque,
                        global const uchar* att, global const uchar4* emis,
                        global uchar* cost, global uchar4* L, int W, int H, int Z) {
    int x = get_global_id(0), y = get_global_id(1);
    uchar carry = LIGHT_MAX;
    for (int z = Z - 1; z >= 0; z--) {
        int i = x + W * (y + H * z);
        ushort b = blocks[i];
        uchar op = opaque[b], a = att[b];
        carry = op ? (uchar)0 : sub_sat(carry, a);
        cost[i] = op ? (uchar)LIGHT_OPAQUE_COST : (uchar)(1 + a);
        uchar4 e = emis[b];
        e.w = carry;
        L[PAD(x, y, z)] = e;
    }
}

// Step 3, one in-place pass: each column sweeps up then down, so vertical propagation
// completes within a pass; reading neighbours mid-update is safe (values only grow,
// never beyond the fixpoint).
kernel void light_relax(global const uchar* cost, global uchar4* L, global int* changed,
                        int W, int H, int Z) {
    int x = get_global_id(0), y = get_global_id(1);
    int sy = W + 2, sz = (W + 2) * (H + 2);
    int i = PAD(x, y, 0), k = x + W * y, ks = W * H;
    int ch = 0;
    for (int z = 0; z < Z; z++, i += sz, k += ks) {
        uchar4 v = L[i], n = light_step(L, i, sy, sz, cost[k]);
        ch |= any(n != v);
        L[i] = n;
    }
    for (int z = Z - 1; z >= 0; z--) {
        i -= sz; k -= ks;
        uchar4 v = L[i], n = light_step(L, i, sy, sz, cost[k]);
        ch |= any(n != v);
        L[i] = n;
    }
    if (ch) changed[0] = 1;
}

kernel void light_pack_out(global const uchar4* L, global ushort* out, int W, int H, int Z) {
    int x = get_global_id(0), y = get_global_id(1);
    for (int z = 0; z < Z; z++)
        out[x + W * (y + H * z)] = light_pack(L[PAD(x, y, z)]);
}
