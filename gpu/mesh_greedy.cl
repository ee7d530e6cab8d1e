// Batched meshing of many tiles (chunks), output compacted with an atomic counter:
// `layers` flags each (tile, z) layer (one item per layer); greedy then runs in `tile`
// (one item per tile: its busy layers, those that can have faces, while they are in
// the cache; a CPU device) or in `band` + `slices` (one item per (tile, direction,
// slice): a GPU, and method "none" everywhere); meshing/cl.py `path` picks. Both
// share mesh_rows.h (the slice views, the greedy on bit rows, the quad records).
#include "mesh_rows.h"

// Per (tile, z): bit 0 = some meshed cell of the layer is not air, bit 1 = the layer
// with its ring is all opaque cubes. One work item per layer z walks its tiles row by
// row: a tile's rows share cache lines with its neighbours', read while they are in
// the cache (an item per (tile, z) read each line twice, from memory: the first
// touch of the block array, the largest kernel before).
__kernel void layers(__global const ushort *P, __constant uchar *flags, int PW, int PH,
                     int nx, int TW, int TH, int ntiles, __global uchar *lay,
                     __global uint *count) {
    int z = get_global_id(0);
    if (z >= 256) return;
    if (z == 0) *count = 0;     // the quad counter of the launch after (one enqueue less)
    __global const ushort *L = P + (long)PW * PH * z;
    for (int t = 0; t < ntiles; t++) {
        __global const ushort *T = L + (t % nx) * TW + (long)PW * ((t / nx) * TH);
        uint any = 0;
        bool opaque = true;
        for (int y = 0; y < TH + 2; y++) {
            __global const ushort *R = T + (long)PW * y;
            uint a = 0;
            bool o = is_opaque(flags, R[0]) && is_opaque(flags, R[TW + 1]);
            for (int x = 1; x <= TW; x++) {
                a |= R[x];
                o &= is_opaque(flags, R[x]);
            }
            if (y > 0 && y <= TH) any |= a;
            opaque &= o;
        }
        lay[t * 256 + z] = (any ? 1 : 0) | (any && opaque ? 2 : 0);
    }
}

// Per tile, 256 bits: layer z (z0 <= z < z1) may have faces: not all air, and not
// sealed (it and the layers above and below all opaque; outside the world is air).
inline uint band_bits(__global const uchar *L, int w, int z0, int z1) {  // layers 32w..
    uint bits = 0;
    for (int k = 0; k < 32; k++) {
        int z = 32 * w + k;
        bool sealed = z > 0 && z < 255 && (L[z - 1] & L[z] & L[z + 1] & 2);
        if (z >= z0 && z < z1 && (L[z] & 1) && !sealed) bits |= 1u << k;
    }
    return bits;
}

__kernel void band(__global const uchar *lay, int z0, int z1, int ntiles,
                   __global uint *busy) {
    int t = get_global_id(0);
    if (t >= ntiles) return;
    for (int w = 0; w < 8; w++) busy[t * 8 + w] = band_bits(lay + t * 256, w, z0, z1);
}

inline bool is_busy(__global const uint *B, int z) { return (B[z >> 5] >> (z & 31)) & 1u; }

// Layers 64w.. of mask k of column c: two 32-bit words (the mask pass writes 8 columns
// of one word as a vector).
inline ulong word64(__global const uint *Mt, int n, int k, int w, int c) {
    __global const uint *m = Mt + (long)(k * 2 * MW + 2 * w) * n + c;
    return (ulong)m[0] | ((ulong)m[n] << 32);
}

#ifdef FLAG_MASKS
// Side face of the 8 cells a toward their neighbours b drawn (0/1 lanes).
inline uint8 vis8(ushort8 a, ushort8 b) {
    uint8 hide = has8(M_OPAQUE, b) | (has8(M_SAME, a) & as_uint8(convert_int8(a == b)) & 1u);
    return has8(M_CUBE, a) & ~hide & 1u;
}

inline void or8(__global uint *m, uint8 lanes, uint one) {
    *(__global uint8 *)m |= lanes * one;     // 32-byte aligned: c is a multiple of 8
}
#endif

// Merge: one work item per tile does all of it while the tile's busy layers are in
// the cache (the kernels per slice each fetched them again: memory-bound on a CPU).
// Per busy layer z (ascending): the X/# planes, both z slices (rows from the layer and
// its neighbours), and per column (x, y) bit z of its x/y masks (a x/y slice's row is
// one column along z): per side direction "drawn", and "same block as below" (cleared
// at region starts: merges stop there). Then the x/y slices from the masks. M: per
// tile MK masks x 8 words of 32 layers x TW*TH columns (uint); words of no busy layer
// are left unwritten.
__kernel void tile(__global const ushort *P, __constant uchar *flags, int PW, int PH,
                   int nx, int TW, int TH, int ntiles, int z0, int z1, int split,
                   __global const uchar *lay, __global uint *M, __global uint4 *out,
                   __global uint *count, uint cap, __global const uint *vt, int nb) {
    Sink sink;
    sink_init(&sink, out, count, cap, vt, nb, split);
    int t = get_global_id(0);
    if (t >= ntiles) return;
    int ox = (t % nx) * TW, oy = (t / nx) * TH, n = TW * TH;
    long PL = (long)PW * PH;
    long base = ox + 1 + (long)PW * (oy + 1);
    __global uint *Mt = M + (long)MK * 2 * MW * n * t;   // [mask][32-layer word][column]
    ulong words[MW];
    for (int w = 0; w < MW; w++) {
        __global const uchar *L = lay + 256 * t;   // the busy layers (as `band`)
        ulong bits = band_bits(L, 2 * w, z0, z1) | ((ulong)band_bits(L, 2 * w + 1, z0, z1) << 32);
        words[w] = bits;
        if (!bits) continue;
        for (int k = 0; k < MK; k++)
            for (int c = 0; c < 2 * n; c++) Mt[(long)(k * 2 * MW + 2 * w) * n + c] = 0;
        while (bits) {
            int k = ctz64(bits);
            bits &= bits - 1;
            int z = 64 * w + k;
            long cz = base + PL * z;
            bool chain = z > 0 && (split == 0 || z % split);
#ifdef CPU_DEVICE
            if (z < 255)    // the layer above: the +z faces' neighbours, often a quiet layer
                for (int y = 0; y < TH; y++) {   // not read since the layer flags: fetch
                    __global const ushort *r = P + cz + PL + (long)PW * y;   // it ahead
                    __builtin_prefetch(r);
                    __builtin_prefetch(r + TW - 1);
                }
#endif
            __global uint *m0 = Mt + (long)(2 * w + (k >> 5)) * n;   // this layer's word
            uint one = 1u << (k & 31);
#ifdef FLAG_MASKS
            if (TW % 8 == 0) {      // 8 columns at once
                for (int y = 0; y < TH; y++)
                    for (int x = 0; x < TW; x += 8) {
                        __global const ushort *A = P + cz + (long)PW * y + x;
                        ushort8 a = ld8(A);
                        if (!any(a != (ushort8)(0))) continue;
                        if (any(has8(M_SHAPE, a) != (uint8)(0)))
                            for (int i = 0; i < 8; i++) shapes(&sink, flags, t, x + i, y, z, A[i]);
                        int c = y * TW + x;
                        long kn = (long)2 * MW * n;
                        uint8 e = chain ? as_uint8(convert_int8(a == ld8(A - PL))) & 1u
                                        : (uint8)(0);
                        or8(m0 + c, vis8(a, ld8(A - 1)), one);
                        or8(m0 + kn + c, vis8(a, ld8(A + 1)), one);
                        or8(m0 + 2 * kn + c, vis8(a, ld8(A - PW)), one);
                        or8(m0 + 3 * kn + c, vis8(a, ld8(A + PW)), one);
                        or8(m0 + 4 * kn + c, e, one);
                    }
            } else
#endif
            for (int y = 0; y < TH; y++)
                for (int x = 0; x < TW; x++) {
                    long c = cz + (long)PW * y + x;
                    ushort b = P[c];
                    if (!b) continue;
                    shapes(&sink, flags, t, x, y, z, b);
                    __global uint *m = m0 + y * TW + x;
                    long kn = (long)2 * MW * n;
                    if (face_key(P, flags, c, -1, false, F_CUBE)) m[0] |= one;
                    if (face_key(P, flags, c, 1, false, F_CUBE)) m[kn] |= one;
                    if (face_key(P, flags, c, -PW, false, F_CUBE)) m[2 * kn] |= one;
                    if (face_key(P, flags, c, PW, false, F_CUBE)) m[3 * kn] |= one;
                    if (chain && b == P[c - PL]) m[4 * kn] |= one;
                }
            span_z(P, flags, cz, PW, -PL, z == 0, TH, TW, t, 4, z, &sink);
            span_z(P, flags, cz, PW, PL, z == 255, TH, TW, t, 5, z, &sink);
        }
    }
    Open o;
    for (int d = 0; d < 4; d++) {
        int a = d >> 1, S = a == 0 ? TW : TH, V = a == 0 ? TH : TW;
        for (int s = 0; s < S; s++) {
            open_init(&o);
            for (int v = 0; v <= V; v++) {
                ulong vis[MW] = {0, 0, 0, 0}, ch[MW] = {0, 0, 0, 0};
                int x = a == 0 ? s : v, y = a == 0 ? v : s;
                if (v < V) {
                    int c = y * TW + x;
                    bool any = false;
                    for (int w = 0; w < MW; w++)
                        if (words[w]) {
                            vis[w] = word64(Mt, n, d, w, c);
                            ch[w] = vis[w] & word64(Mt, n, 4, w, c);
                            any |= vis[w] != 0;
                        }
                    if (!any && !o.nopen) continue;
                }
                row_step(&o, vis, ch, v, P + base + x + (long)PW * y, PL, &sink, t, d, s);
            }
        }
    }
    flush(&sink);
}

// ---- per-slice kernels (`slices`: greedy on a GPU, method "none" everywhere) -------
// Work items per tile: 2*TW x-slices and 2*TH y-slices (each walks its render regions
// and, in them, the runs of busy layers: quiet layers have no faces, so cutting there
// changes nothing), then 2*ZK z items (each takes every ZK-th busy layer). Many items
// per tile keep a GPU busy (`tile`'s one per tile leaves it idle: meshing/cl.py picks);
// pocl runs a work group's items as one loop, so idle or divergent ones cost there.
#define ZK 8

__kernel void slices(__global const ushort *P, __constant uchar *flags, int PW, int PH,
                     int nx, int TW, int TH, int ntiles, int z0, int z1, int split, int nreg,
                     int merge, __global const uint *busy, __global uint4 *out,
                     __global uint *count, uint cap, __global const uint *vt, int nb) {
    Sink sink;
    sink_init(&sink, out, count, cap, vt, nb, split);
    int ni = 2 * (TW + TH) + 2 * ZK;
    int t = get_global_id(0) / ni, i = get_global_id(0) % ni;
    if (t >= ntiles) return;
    __global const uint *B = busy + 8 * t;
    int ox = (t % nx) * TW, oy = (t / nx) * TH;
    long PL = (long)PW * PH;
    int d, s;
    if (i < 2 * TW) { d = i / TW; s = i % TW; }
    else if ((i -= 2 * TW) < 2 * TH) { d = 2 + i / TH; s = i % TH; }
    else { i -= 2 * TH; d = 4 + i / ZK; s = i % ZK; }
    int a = d >> 1;
    long step = a == 0 ? 1 : (a == 1 ? PW : PL);
    if (!(d & 1)) step = -step;
    uint want = a == 2 ? (F_CUBE | F_CAP) : F_CUBE;
    if (a < 2) {
        int V = a == 0 ? TH : TW;
        long c0 = a == 0 ? (ox + s + 1) + (long)PW * (oy + 1) : (ox + 1) + (long)PW * (oy + s + 1);
        long sv = a == 0 ? PW : 1;
        for (int r = 0; r < nreg; r++) {
            int rs = r == 0 ? z0 : (z0 / split + r) * split;
            int re = split ? min((z0 / split + r + 1) * split, z1) : z1;
            for (int u = rs; u < re;) {
                if (!is_busy(B, u)) { u++; continue; }
                int u1 = u + 1;
                while (u1 < re && is_busy(B, u1)) u1++;
                if (merge) span_greedy(P, flags, c0, sv, PL, step, want, V, u, u1, t, d, s, &sink);
                else span(P, flags, c0, sv, PL, step, false, want, V, u, u1, t, d, s, &sink);
                u = u1;
            }
        }
        flush(&sink);
        return;
    }
    for (int z = z0 + s; z < z1; z += ZK) {
        if (!is_busy(B, z)) continue;
        long c0 = (ox + 1) + (long)PW * (oy + 1) + PL * z;
        if (d == 4)  // X and # planes of this layer, once per cell
            for (int v = 0; v < TH; v++)
                for (int u = 0; u < TW; u++) shapes(&sink, flags, t, u, v, z, P[c0 + v * PW + u]);
        bool edge = (d == 4 && z == 0) || (d == 5 && z == 255);
        if (merge) span_z(P, flags, c0, PW, step, edge, TH, TW, t, d, z, &sink);
        else span(P, flags, c0, PW, 1, step, edge, want, TH, 0, TW, t, d, z, &sink);
    }
    flush(&sink);
}
