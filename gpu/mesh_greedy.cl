// Batched meshing of many tiles (chunks) in three launches, output compacted with an
// atomic counter: `layers` flags each (tile, z) layer, `band` turns them into the z
// range that can have faces, `greedy` aggregates (or, merge == 0, lists unit faces)
// one (tile, direction, slice, region) per work item and appends the quads.
//
// Slice views as meshing/faces.py: axis x -> (s, v, u) = (x, y, z); axis y -> (y, x, z);
// axis z -> (z, y, x). Greedy is Mikola's scan order run row by row: open rectangles
// continue while the whole row under them has their key; free cells start maximal
// runs. This needs only per-column state (private arrays of UMAX), not a seen mask.
#include "mesh.h"

#define UMAX 256
#define NONE 0xFFFF

// bit 0: some meshed cell of the layer is not air; bit 1: the whole layer with its
// ring is opaque cubes (a layer sandwiched by such layers has no faces).
__kernel void layers(__global const ushort *P, __constant uchar *flags, int PW, int PH,
                     int nx, int TW, int TH, int ntiles, __global uchar *lay) {
    int t = get_global_id(0) / 256, z = get_global_id(0) % 256;
    if (t >= ntiles) return;
    int ox = (t % nx) * TW, oy = (t / nx) * TH;
    bool any = false, opaque = true;
    for (int y = 0; y < TH + 2; y++) {
        long c = ox + (long)PW * (oy + y + (long)PH * z);
        for (int x = 0; x < TW + 2; x++) {
            ushort a = P[c + x];
            opaque &= (flags[a] & F_OPAQUE) != 0;
            any |= a != 0 && x > 0 && x <= TW && y > 0 && y <= TH;
        }
    }
    lay[t * 256 + z] = (any ? 1 : 0) | (opaque ? 2 : 0);
}

__kernel void band(__global const uchar *lay, int z0, int z1, int ntiles,
                   __global int2 *out) {
    int t = get_global_id(0);
    if (t >= ntiles) return;
    __global const uchar *L = lay + t * 256;
    int lo = 256, hi = 0;
    for (int z = z0; z < z1; z++) {
        bool sealed = z > 0 && z < 255 && (L[z - 1] & L[z] & L[z + 1] & 2);
        if ((L[z] & 1) && !sealed) { lo = min(lo, z); hi = z + 1; }
    }
    out[t] = (int2)(lo, hi);
}

// Record: (tile, x | y << 16, z | face << 8 | block << 16, w | h << 16), tile-local.
inline void put(__global uint4 *out, __global uint *count, uint cap, int t, int x, int y,
                int z, int face, int w, int h, uint block) {
    uint slot = atomic_inc(count);
    if (slot < cap)
        out[slot] = (uint4)((uint)t, (uint)x | ((uint)y << 16),
                            (uint)z | ((uint)face << 8) | (block << 16), (uint)w | ((uint)h << 16));
}

// Rect in slice view (rows v.., columns u..) -> quad fields (faces.py _VIEW, rects_to_quads).
inline void put_rect(__global uint4 *out, __global uint *count, uint cap, int t, int d,
                     int s, int v, int u, int rows, int cols, uint block) {
    int a = d >> 1;
    if (a == 0) put(out, count, cap, t, s, v, u, d, rows, cols, block);
    else if (a == 1) put(out, count, cap, t, v, s, u, d, rows, cols, block);
    else put(out, count, cap, t, u, v, s, d, cols, rows, block);
}

__kernel void greedy(__global const ushort *P, __constant uchar *flags, int PW, int PH,
                     int nx, int TW, int TH, int ntiles, int z0, int z1, int split, int nreg,
                     int merge, __global const int2 *bands, __global uint4 *out,
                     __global uint *count, uint cap) {
    int ni = 2 * (TW + TH) * nreg + 2 * (z1 - z0);
    int t = get_global_id(0) / ni, i = get_global_id(0) % ni;
    if (t >= ntiles) return;
    int2 bd = bands[t];
    if (bd.x >= bd.y) return;
    int ox = (t % nx) * TW, oy = (t / nx) * TH;
    long PL = (long)PW * PH;
    int d, s, r = 0;
    if (i < 2 * TW * nreg) { d = i / (TW * nreg); s = i % (TW * nreg); }
    else if ((i -= 2 * TW * nreg) < 2 * TH * nreg) { d = 2 + i / (TH * nreg); s = i % (TH * nreg); }
    else { i -= 2 * TH * nreg; d = 4 + i / (z1 - z0); s = z0 + i % (z1 - z0); }
    int a = d >> 1;
    int V, ulo, uhi;
    long c0, sv, su;
    if (a < 2) {
        r = s % nreg; s /= nreg;
        int rs = r == 0 ? z0 : (z0 / split + r) * split;
        int re = split ? min((z0 / split + r + 1) * split, z1) : z1;
        ulo = max(rs, bd.x); uhi = min(re, bd.y);
        if (ulo >= uhi) return;
        V = a == 0 ? TH : TW;
        su = PL;
        if (a == 0) { c0 = (ox + s + 1) + (long)PW * (oy + 1); sv = PW; }
        else { c0 = (ox + 1) + (long)PW * (oy + s + 1); sv = 1; }
    } else {
        if (s < bd.x || s >= bd.y) return;
        ulo = 0; uhi = TW; V = TH;
        c0 = (ox + 1) + (long)PW * (oy + 1) + PL * s; sv = PW; su = 1;
    }
    long step = a == 0 ? 1 : (a == 1 ? PW : PL);
    if (!(d & 1)) step = -step;
    bool edge = (d == 4 && s == 0) || (d == 5 && s == 255);
    uint want = a == 2 ? (F_CUBE | F_CAP) : F_CUBE;

    if (d == 4) {  // X and # planes of this layer, once per cell
        for (int v = 0; v < V; v++)
            for (int u = 0; u < TW; u++) {
                ushort b = P[c0 + v * sv + u];
                uint f = flags[b];
                if (f & F_X) { put(out, count, cap, t, u, v, s, 6, 1, 1, b);
                               put(out, count, cap, t, u, v, s, 7, 1, 1, b); }
                if (f & F_HASH)
                    for (int k = 8; k < 12; k++) put(out, count, cap, t, u, v, s, k, 1, 1, b);
            }
    }
    if (!merge) {
        for (int v = 0; v < V; v++)
            for (int u = ulo; u < uhi; u++) {
                ushort k = face_key(P, flags, c0 + v * sv + u * su, step, edge, want);
                if (k) put_rect(out, count, cap, t, d, s, v, u, 1, 1, k);
            }
        return;
    }
    ushort ost[UMAX], okey[UMAX], ow[UMAX], orow[UMAX];
    for (int u = ulo; u < uhi; u++) ost[u] = NONE;
    for (int v = 0; v < V; v++) {
        long cv = c0 + v * sv;
        for (int u = ulo; u < uhi;) {       // open rectangles: continue or close
            if (ost[u] != u) { u++; continue; }
            int w = ow[u];
            ushort k = okey[u];
            bool ok = true;
            for (int j = 0; j < w && ok; j++)
                ok = face_key(P, flags, cv + (u + j) * su, step, edge, want) == k;
            if (!ok) {
                put_rect(out, count, cap, t, d, s, orow[u], u, v - orow[u], w, k);
                for (int j = 0; j < w; j++) ost[u + j] = NONE;
            }
            u += w;
        }
        for (int u = ulo; u < uhi;) {       // free cells: new maximal runs
            if (ost[u] != NONE) { u++; continue; }
            ushort k = face_key(P, flags, cv + u * su, step, edge, want);
            if (!k) { u++; continue; }
            int w = 1;
            while (u + w < uhi && ost[u + w] == NONE
                   && face_key(P, flags, cv + (u + w) * su, step, edge, want) == k) w++;
            for (int j = 0; j < w; j++) ost[u + j] = u;
            okey[u] = k; ow[u] = w; orow[u] = v;
            u += w;
        }
    }
    for (int u = ulo; u < uhi; u++)
        if (ost[u] == u) put_rect(out, count, cap, t, d, s, orow[u], u, V - orow[u], ow[u], okey[u]);
}
