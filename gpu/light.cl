// Full light solve of a (W4, H, Z) block slab with open sky above it and dark air
// around; W4 = 4G (the host pads x with a block of cost 255 and no emission). x is
// grouped by 4: a work-item handles 4 adjacent voxels as one uchar16.
// Blocks are unpadded (x + W4*(y + H*z)). Lanes L (4 bytes/voxel) and cost (1 byte)
// live in a padded grid: x in [-4, SX-4), y in [-1, H+1), z in [-1, Z+1), SX = W4 + 8;
// padding has lanes 0 and cost 255: the model's dark air outside, never changing.
// Host (voxel_addon/light/cl.py): light_start, directional line sweeps z, x, y, z, ...
// until two in a row change nothing, light_pack_out.
//
// A sweep runs each dirty line forth and back with v = max(v, prev - cost): light
// travels any distance along the axis in one sweep. Dirty flags, one byte per 16-voxel
// segment of a line: dz[(g + G*y)*NSZ + z/16], dy[(g + G*z)*NSY + y/16],
// dx[(y + H*z)*NSX + x/16]. Invariant: a line can only be raised along itself within
// 15 voxels of a dirty segment (a raise is a path of <= 14 steps from a changed voxel).
// A sweep clears its line's flags, runs the window [first dirty - 15, last dirty + 15]
// and marks the crossing lines of the other two axes at every voxel it raises. So a
// sweep of axis A followed by two that change nothing leaves no dirty line: fixpoint.
// The first z sweep runs every column range whole and marks the x/y segments of every
// voxel a horizontal neighbour can raise right now. Lines of one sweep are disjoint,
// so items never touch each other's voxels.
#include "light.h"

#define IDX(x, y, z) (((x) + 4) + SX * (((y) + 1) + (H + 2) * ((z) + 1)))
#define SEG 16
#define BLOCK 8  // groups of 4 columns per item in light_start / sweep_z / sweep_y
#define NSX (((SX - 8) / 4 + 3) / 4)
#define NSY ((H + SEG - 1) / SEG)
#define NSZ ((Z + SEG - 1) / SEG)

// Steps 1-2 for the columns of block k (groups [8k, 8k+8)) of row y, walking z down
// a layer at a time so memory runs contiguous: emission and the daylight column pass
// (a voxel's carry is the D of the voxel above). tab[id] = (R, G, B, cost). Per column
// for the host (info = 3 planes [H][W4]): lowest non-opaque z, 1 + highest
// non-opaque z with D < 15, top emitter z (-1: none).
kernel void light_start(global const ushort* blocks, global const uchar4* tab,
                        global uchar* cost, global uchar* L, global int* info,
                        int H, int Z, int SX) {
    int k = get_global_id(0), y = get_global_id(1), W4 = SX - 8, G = W4 / 4;
    int g0 = BLOCK * k, g1 = min(G, g0 + BLOCK), sz = SX * (H + 2), n = W4 * H;
    int4 lo[BLOCK], hi[BLOCK], em[BLOCK];
    for (int j = 0; j < BLOCK; j++) { lo[j] = (int4)(Z); hi[j] = (int4)(0); em[j] = (int4)(-1); }
    for (int z = Z - 1; z >= 0; z--) {
        for (int g = g0; g < g1; g++) {
            int x = 4 * g, i = IDX(x, y, z);
            ushort4 b = vload4(0, blocks + x + W4 * (y + H * z));
            uchar4 t0 = tab[b.x], t1 = tab[b.y], t2 = tab[b.z], t3 = tab[b.w];
            uchar4 c = (uchar4)(t0.w, t1.w, t2.w, t3.w);
            uchar4 carry = (uchar4)(LIGHT_MAX);
            if (z < Z - 1) carry = vload16(0, L + 4 * (i + sz)).s37bf;
            char4 op = as_char4(c == (uchar4)(LIGHT_OPAQUE_COST));
            carry = select(sub_sat(carry, c - (uchar4)(1)), (uchar4)(0), op);
            vstore4(c, 0, cost + i);
            vstore16((uchar16)(t0.xyz, carry.x, t1.xyz, carry.y, t2.xyz, carry.z,
                               t3.xyz, carry.w), 0, L + 4 * i);
            int4 clear = convert_int4(op) == (int4)(0);
            int4 l = lo[g - g0], h = hi[g - g0], e = em[g - g0];
            l = select(l, (int4)(z), clear);
            h = select(h, (int4)(z + 1), clear & convert_int4(carry < (uchar4)(LIGHT_MAX))
                                           & (h == (int4)(0)));
            uchar4 lit = (uchar4)(t0.x | t0.y | t0.z, t1.x | t1.y | t1.z, t2.x | t2.y | t2.z,
                                  t3.x | t3.y | t3.z);
            e = select(e, (int4)(z), convert_int4(lit != (uchar4)(0)) & (e < (int4)(0)));
            lo[g - g0] = l; hi[g - g0] = h; em[g - g0] = e;
        }
    }
    for (int g = g0; g < g1; g++) {
        int o = 4 * g + W4 * y;
        vstore4(lo[g - g0], 0, info + o);
        vstore4(hi[g - g0], 0, info + n + o);
        vstore4(em[g - g0], 0, info + 2 * n + o);
    }
}

// First dirty window of a line's segment flags (clearing them), as [a, b) clipped
// to [0, n); a >= b when the line is clean.
inline int2 light_window(global uchar* fl, int nseg, int n) {
    int s0 = -1, s1 = -1;
    for (int s = 0; s < nseg; s++)
        if (fl[s]) { if (s0 < 0) s0 = s; s1 = s; fl[s] = 0; }
    if (s0 < 0) return (int2)(0, 0);
    return (int2)(max(0, s0 * SEG - 15), min(n, (s1 + 1) * SEG + 15));
}

// z lines of the groups of block k at row y, each within its range [lo, hi) (outside
// it nothing can change; the voxels just outside still feed the line). The block's
// lines advance together, a layer at a time, so memory runs contiguous.
kernel void light_sweep_z(global uchar* L, global const uchar* cost, global const int2* range,
                          global uchar* dz, global uchar* dy, global uchar* dx,
                          global int* changed, int init, int H, int Z, int SX) {
    int k = get_global_id(0), y = get_global_id(1), G = (SX - 8) / 4;
    int g0 = BLOCK * k, g1 = min(G, g0 + BLOCK), sz = SX * (H + 2);
    int2 w[BLOCK];
    int za = Z, zb = 0, ch = 0, my = y / SEG;
    for (int g = g0; g < g1; g++) {
        int2 r = range[g + G * y];
        if (!init) {
            int2 d = light_window(dz + (g + G * y) * NSZ, NSZ, Z);
            r = (int2)(max(r.x, d.x), min(r.y, d.y));
        }
        w[g - g0] = r;
        if (r.x < r.y) { za = min(za, r.x); zb = max(zb, r.y); }
    }
    for (int z = za; z < zb; z++)
        for (int g = g0; g < g1; g++) {
            int2 r = w[g - g0];
            if (z < r.x || z >= r.y) continue;
            int i = IDX(4 * g, y, z);
            uchar16 v = vload16(0, L + 4 * i);
            uchar16 n = light_spread4(v, vload16(0, L + 4 * (i - sz)), vload4(0, cost + i));
            if (any(n != v)) {
                vstore16(n, 0, L + 4 * i);
                dy[(g + G * z) * NSY + my] = 1; dx[(y + H * z) * NSX + g / 4] = 1; ch = 1;
            }
        }
    for (int z = zb - 1; z >= za; z--)
        for (int g = g0; g < g1; g++) {
            int2 r = w[g - g0];
            if (z < r.x || z >= r.y) continue;
            int i = IDX(4 * g, y, z);
            uchar16 v = vload16(0, L + 4 * i);
            uchar4 c = vload4(0, cost + i);
            uchar16 n = light_spread4(v, vload16(0, L + 4 * (i + sz)), c);
            int up = any(n != v);
            if (up) { vstore16(n, 0, L + 4 * i); ch = 1; }
            int rx = up, ry = up;
            if (init && !up) {  // can a horizontal neighbour raise these 4 voxels?
                rx = light_raises4(vload16(0, L + 4 * (i - 1)), n, c)
                   | light_raises4(vload16(0, L + 4 * (i + 1)), n, c);
                ry = light_raises4(vload16(0, L + 4 * (i - SX)), n, c)
                   | light_raises4(vload16(0, L + 4 * (i + SX)), n, c);
            }
            if (ry) dy[(g + G * z) * NSY + my] = 1;
            if (rx) dx[(y + H * z) * NSX + g / 4] = 1;
        }
    if (ch) changed[0] = 1;
}

// y lines of the groups of block k at height z, advancing together a row at a time.
kernel void light_sweep_y(global uchar* L, global const uchar* cost,
                          global uchar* dz, global uchar* dy, global uchar* dx,
                          global int* changed, int H, int Z, int SX) {
    int k = get_global_id(0), z = get_global_id(1), G = (SX - 8) / 4;
    int g0 = BLOCK * k, g1 = min(G, g0 + BLOCK);
    int2 w[BLOCK];
    int ya = H, yb = 0, ch = 0, mz = z / SEG;
    for (int g = g0; g < g1; g++) {
        int2 r = light_window(dy + (g + G * z) * NSY, NSY, H);
        w[g - g0] = r;
        if (r.x < r.y) { ya = min(ya, r.x); yb = max(yb, r.y); }
    }
    for (int y = ya; y < yb; y++)
        for (int g = g0; g < g1; g++) {
            int2 r = w[g - g0];
            if (y < r.x || y >= r.y) continue;
            int i = IDX(4 * g, y, z);
            uchar16 v = vload16(0, L + 4 * i);
            uchar16 n = light_spread4(v, vload16(0, L + 4 * (i - SX)), vload4(0, cost + i));
            if (any(n != v)) {
                vstore16(n, 0, L + 4 * i);
                dz[(g + G * y) * NSZ + mz] = 1; dx[(y + H * z) * NSX + g / 4] = 1; ch = 1;
            }
        }
    for (int y = yb - 1; y >= ya; y--)
        for (int g = g0; g < g1; g++) {
            int2 r = w[g - g0];
            if (y < r.x || y >= r.y) continue;
            int i = IDX(4 * g, y, z);
            uchar16 v = vload16(0, L + 4 * i);
            uchar16 n = light_spread4(v, vload16(0, L + 4 * (i + SX)), vload4(0, cost + i));
            if (any(n != v)) {
                vstore16(n, 0, L + 4 * i);
                dz[(g + G * y) * NSZ + mz] = 1; dx[(y + H * z) * NSX + g / 4] = 1; ch = 1;
            }
        }
    if (ch) changed[0] = 1;
}

// x line at (y, z), 4 voxels per step, the scan running through them in registers.
kernel void light_sweep_x(global uchar* L, global const uchar* cost,
                          global uchar* dz, global uchar* dy, global uchar* dx,
                          global int* changed, int H, int Z, int SX) {
    int y = get_global_id(0), z = get_global_id(1), G = (SX - 8) / 4;
    int2 r = light_window(dx + (y + H * z) * NSX, NSX, 4 * G);
    if (r.x >= r.y) return;
    int g0 = r.x / 4, g1 = (r.y + 3) / 4;
    int i = IDX(4 * g0, y, z), ch = 0, my = y / SEG, mz = z / SEG;
    uchar4 p = vload4(0, L + 4 * (i - 1));
    for (int g = g0; g < g1; g++, i += 4) {
        uchar16 v = vload16(0, L + 4 * i);
        uchar4 c = vload4(0, cost + i);
        uchar4 a = max(v.s0123, sub_sat(p, (uchar4)(c.x)));
        uchar4 b = max(v.s4567, sub_sat(a, (uchar4)(c.y)));
        uchar4 d = max(v.s89ab, sub_sat(b, (uchar4)(c.z)));
        p = max(v.scdef, sub_sat(d, (uchar4)(c.w)));
        uchar16 n = (uchar16)(a, b, d, p);
        if (any(n != v)) {
            vstore16(n, 0, L + 4 * i);
            dz[(g + G * y) * NSZ + mz] = 1; dy[(g + G * z) * NSY + my] = 1; ch = 1;
        }
    }
    p = vload4(0, L + 4 * i);
    for (int g = g1 - 1; g >= g0; g--) {
        i -= 4;
        uchar16 v = vload16(0, L + 4 * i);
        uchar4 c = vload4(0, cost + i);
        uchar4 d = max(v.scdef, sub_sat(p, (uchar4)(c.w)));
        uchar4 b = max(v.s89ab, sub_sat(d, (uchar4)(c.z)));
        uchar4 a = max(v.s4567, sub_sat(b, (uchar4)(c.y)));
        p = max(v.s0123, sub_sat(a, (uchar4)(c.x)));
        uchar16 n = (uchar16)(p, a, b, d);
        if (any(n != v)) {
            vstore16(n, 0, L + 4 * i);
            dz[(g + G * y) * NSZ + mz] = 1; dy[(g + G * z) * NSY + my] = 1; ch = 1;
        }
    }
    if (ch) changed[0] = 1;
}

// Packed SPEC §3 light, (W4, H, Z) unpadded; one x row per item.
kernel void light_pack_out(global const uchar* L, global ushort* out, int H, int Z, int SX) {
    int y = get_global_id(0), z = get_global_id(1), W4 = SX - 8;
    global const uchar* src = L + 4 * IDX(0, y, z);
    global ushort* dst = out + W4 * (y + H * z);
    for (int g = 0; g < W4 / 4; g++) vstore4(light_pack4(vload16(g, src)), g, dst);
}
