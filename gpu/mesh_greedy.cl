// Batched meshing of many tiles (chunks), output compacted with an atomic counter:
// `layers` flags each (tile, z) layer (one item per layer); greedy then runs in `tile`
// (one item per tile: its busy layers, those that can have faces, while they are in
// the cache; a CPU device) or in `band` + `slices` (one item per (tile, direction,
// slice): a GPU, and method "none" everywhere); meshing/cl.py `path` picks.
//
// Slice views as meshing/faces.py: axis x -> (s, v, u) = (x, y, z); axis y -> (y, x, z);
// axis z -> (z, y, x). Greedy is Mikola's scan order run row by row: open rectangles
// continue while the whole row under them has their key; free cells start maximal
// runs. This needs only per-column state (private arrays of UMAX), not a seen mask;
// rows are bit masks (`row_step`), at most 256 columns.
#include "mesh.h"

#define UMAX 256

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

// Where quads go. Without vertices (nb == 0) two uint4 per quad: (tile, x | y << 16,
// z | face << 8 | block << 16, w | h << 16), tile-local, unused. With them (nb > 0,
// 16 x 16 tiles, meshing/vertex.py `_from_records`) three: the order key (lo = z << 8 |
// y << 4 | x, hi = ((tile * regions + region) * 4 + pass) << 4 | face), the 17 bytes
// of the quad's meshing.QUAD record (colour 0) and the tile; then its four packed
// viewport vertices (vertex.py `_pack`). vt holds the tables: per face code and
// corner the position offsets A, B, C at 0, 48, 96; per block the animation bits at
// 144, the # inset bits at 144 + nb, the texture layer per face code at 144 + 2 nb,
// the render pass at 144 + 14 nb. The host then sorts and slices, nothing per field;
// z is region-local in the vertices (split: the region height).
// A work item collects SB quads and then takes their slots with one atomic add (an
// atomic per quad on a shared counter cost more than writing the quad).
#define SB 32
typedef struct {
    __global uint4 *out;
    __global uint *count;
    uint cap;
    __global const uint *vt;
    int nb, split, n, w;
    uint4 buf[3 * SB];
} Sink;

inline void sink_init(Sink *k, __global uint4 *out, __global uint *count, uint cap,
                      __global const uint *vt, int nb, int split) {
    k->out = out; k->count = count; k->cap = cap; k->vt = vt; k->nb = nb; k->split = split;
    k->n = 0;
    k->w = nb ? 3 : 2;
}

inline void flush(Sink *k) {
    if (!k->n) return;
    uint slot = atomic_add(k->count, (uint)k->n);
    int used = k->nb ? 3 : 1;
    for (int i = 0; i < k->n && slot + i < k->cap; i++)
        for (int j = 0; j < used; j++) k->out[k->w * (slot + i) + j] = k->buf[k->w * i + j];
    k->n = 0;
}

inline void put(Sink *k, int t, int x, int y, int z, int face, int w, int h, uint block) {
    uint4 *r = k->buf + k->w * k->n;
    uint uw = (uint)w, uh = (uint)h;
    if (!k->nb) {
        r[0] = (uint4)((uint)t, (uint)x | ((uint)y << 16), (uint)z | ((uint)face << 8) | (block << 16),
                       uw | (uh << 16));
    } else {
        __global const uint *vt = k->vt;
        int nb = k->nb;
        uint layer = vt[144 + 2 * nb + block * 12 + face];
        uint pass = vt[144 + 14 * nb + block];
        uint nreg = k->split ? 256 / k->split : 1, reg = k->split ? z / k->split : 0;
        uint zl = (uint)z - reg * (uint)k->split;
        r[0] = (uint4)(((uint)z << 8) | ((uint)y << 4) | (uint)x,
                       ((((uint)t * nreg + reg) * 4 + pass) << 4) | (uint)face,
                       (uint)x | ((uint)y << 16),
                       (uint)z | ((uint)face << 16) | ((uw & 0xFF) << 24));
        r[1] = (uint4)((uw >> 8) | (uh << 8) | ((block & 0xFF) << 24),
                       (block >> 8) | (layer << 8), 0u, (uint)t);
        uint base = (uint)x | ((uint)y << 5) | (zl << 10) | ((uint)face << 17)
                    | (layer << 21) | vt[144 + block] | (face >= 8 ? vt[144 + nb + block] : 0u);
        int c = 4 * face;
        r[2] = (uint4)(base + vt[c] * uw + vt[48 + c] * uh + vt[96 + c],
                       base + vt[c + 1] * uw + vt[49 + c] * uh + vt[97 + c],
                       base + vt[c + 2] * uw + vt[50 + c] * uh + vt[98 + c],
                       base + vt[c + 3] * uw + vt[51 + c] * uh + vt[99 + c]);
    }
    if (++k->n == SB) flush(k);
}

// Rect in slice view (rows v.., columns u..) -> quad fields (as faces.aggregate_pieces).
inline void put_rect(Sink *k, int t, int d, int s, int v, int u, int rows, int cols, uint block) {
    int a = d >> 1;
    if (a == 0) put(k, t, s, v, u, d, rows, cols, block);
    else if (a == 1) put(k, t, v, s, u, d, rows, cols, block);
    else put(k, t, u, v, s, d, cols, rows, block);
}

// Unit faces (method "none") over columns [ulo, uhi) of one slice.
inline void span(__global const ushort *P, __constant uchar *flags, long c0, long sv, long su,
                 long step, bool edge, uint want, int V, int ulo, int uhi,
                 int t, int d, int s, Sink *sink) {
    for (int v = 0; v < V; v++)
        for (int u = ulo; u < uhi; u++) {
            ushort k = face_key(P, flags, c0 + v * sv + u * su, step, edge, want);
            if (k) put_rect(sink, t, d, s, v, u, 1, 1, k);
        }
}

// ---- greedy on bit masks (merge: `tile`) -------------------------------------------
// The same greedy as `span`, on rows of bits: a row is "drawn" bits (key != 0) and
// "chained" bits (drawn and the same block as the cell before); an open rectangle
// continues while its cells are drawn and chained and its first cell has its key (one
// load); free cells are found with bit scans. Equal keys of drawn cells are equal
// blocks, so the rects are those of `span`.
#define MW 4              // ulong words per 256-bit row
#define MK 5              // masks per column: drawn for d = 0..3, "same" as below

// CPU_DEVICE (meshing/cl.py, pocl on the CPU): clang's builtin, one instruction (OpenCL
// C 1.2 has no ctz, and pocl did not inline popcount); elsewhere the portable form.
#ifdef CPU_DEVICE
inline int ctz64(ulong x) { return __builtin_ctzll(x); }
#else
inline int ctz64(ulong x) { return (int)popcount((x & (0 - x)) - 1); }
#endif

// How many bits of m are set in a row from bit i on.
inline int ones_from(const ulong *m, int i) {
    int n = 0;
    while (i < 64 * MW) {
        int avail = 64 - (i & 63);
        ulong inv = ~(m[i >> 6] >> (i & 63));   // the shifted-in top bits read as unset
        int k = inv ? ctz64(inv) : 64;
        k = k < avail ? k : avail;
        n += k;
        i += k;
        if (k < avail) break;
    }
    return n;
}

inline void clear_bits(ulong *m, int a, int b) {  // bits [a, b)
    for (int i = a; i < b;) {
        int k = b - i < 64 - (i & 63) ? b - i : 64 - (i & 63);
        ulong r = (k == 64 ? ~0UL : ((1UL << k) - 1)) << (i & 63);
        m[i >> 6] &= ~r;
        i += k;
    }
}

// The greedy's state over one slice: open rectangles by start column (bits `os`,
// their cells `occ`; key, width and first row at the start column).
typedef struct {
    ulong os[MW], occ[MW];
    int nopen;
    ushort okey[UMAX], ow[UMAX], orow[UMAX];
} Open;

inline void set_bits(ulong *m, int a, int b) {  // bits [a, b)
    for (int i = a; i < b;) {
        int k = b - i < 64 - (i & 63) ? b - i : 64 - (i & 63);
        m[i >> 6] |= (k == 64 ? ~0UL : ((1UL << k) - 1)) << (i & 63);
        i += k;
    }
}

// One row v of a slice (v == V: past the last row, closes everything): vis = the
// drawn cells, ch = drawn and the same block as the cell before (u - 1); the key of
// cell u is K[ku * u]. Rects: put_rect(t, d, s, first row, u, rows, columns, key).
inline void row_step(Open *o, ulong *vis, const ulong *ch, int v, __global const ushort *K,
                     long ku, Sink *sink, int t, int d, int s) {
    for (int w = 0; w < MW && o->nopen; w++) {  // open rectangles: continue or close
        ulong b = o->os[w];
        while (b) {
            int u = 64 * w + ctz64(b);
            b &= b - 1;
            int wd = o->ow[u];
            if (((vis[w] >> (u & 63)) & 1UL) && (wd == 1 || ones_from(ch, u + 1) >= wd - 1)
                && K[ku * u] == o->okey[u])
                continue;
            put_rect(sink, t, d, s, o->orow[u], u, v - o->orow[u], wd, o->okey[u]);
            o->os[w] &= ~(1UL << (u & 63));
            clear_bits(o->occ, u, u + wd);
            o->nopen--;
        }
    }
    ulong fc[MW];     // free cells start maximal runs (fc: free and the same as before)
    for (int w = 0; w < MW; w++) { vis[w] &= ~o->occ[w]; fc[w] = ch[w] & vis[w]; }
    for (int w = 0; w < MW; w++) {
        while (vis[w]) {
            int u = 64 * w + ctz64(vis[w]);
            int wd = 1 + ones_from(fc, u + 1);
            clear_bits(vis, u, u + wd);
            set_bits(o->occ, u, u + wd);
            o->os[w] |= 1UL << (u & 63);
            o->okey[u] = K[ku * u]; o->ow[u] = wd; o->orow[u] = v;
            o->nopen++;
        }
    }
}

inline void open_init(Open *o) {
    for (int w = 0; w < MW; w++) o->os[w] = o->occ[w] = 0;
    o->nopen = 0;
}

#ifdef FLAG_MASKS
// Rows of 16 cells as two 8-lane halves (256-bit vectors: wider ones change the ABI
// without AVX-512); the 64-bit flag masks as 32-bit halves (ids < 64 here).
inline uint8 has8(ulong m, ushort8 id) {
    uint8 i = convert_uint8(id);
    uint8 lo = (uint8)((uint)m), hi = (uint8)((uint)(m >> 32));
    uint8 w = lo ^ ((lo ^ hi) & as_uint8(i >= (uint8)(32)));
    return (w >> (i & 31u)) & 1u;
}

// An unaligned 8-lane load (pocl's vload8 was a call here, not inlined).
#ifdef CPU_DEVICE
typedef ushort8 __attribute__((aligned(2))) ushort8_u;
inline ushort8 ld8(__global const ushort *p) { return *(__global const ushort8_u *)p; }
#else
inline ushort8 ld8(__global const ushort *p) { return vload8(0, p); }
#endif

inline uint bits8(uint8 b) {     // lane i (0/1) -> bit i
    b <<= (uint8)(0, 1, 2, 3, 4, 5, 6, 7);
    uint4 q = b.lo | b.hi;
    uint2 p = q.lo | q.hi;
    return p.x | p.y;
}

inline uint row8(__global const ushort *A, long step, ulong want) {
    ushort8 a = ld8(A);
    ushort8 b = step ? ld8(A + step) : (ushort8)(0);
    uint8 hide = has8(M_OPAQUE, b) | (has8(M_SAME, a) & as_uint8(convert_int8(a == b)) & 1u);
    return bits8(has8(want, a) & ~hide & 1u);
}

// face_key != 0 of the 16 cells at A toward A + step (step 0: toward air), as bits.
inline ulong row16(__global const ushort *A, long step, ulong want) {
    return (ulong)row8(A, step, want) | ((ulong)row8(A + 8, step, want) << 8);
}

// Cell u is the same block as cell u - 1 (u >= 1), as bits.
inline ulong same16(__global const ushort *A) {
    uint lo = bits8(as_uint8(convert_int8(ld8(A) == ld8(A - 1))) & 1u);
    uint hi = bits8(as_uint8(convert_int8(ld8(A + 8) == ld8(A + 7))) & 1u);
    return ((ulong)lo | ((ulong)hi << 8)) & ~1UL;
}
#endif

// A z slice (rows v = y, columns u = x, both from the cells' P at c0 + v * PW + u).
inline void span_z(__global const ushort *P, __constant uchar *flags, long c0, int PW,
                   long step, bool edge, int V, int U, int t, int d, int s, Sink *sink) {
    Open o;
    open_init(&o);
    for (int v = 0; v <= V; v++) {
        ulong vis[MW] = {0, 0, 0, 0}, ch[MW] = {0, 0, 0, 0};
        long cv = c0 + (long)v * PW;
        if (v < V) {
#ifdef FLAG_MASKS
            if (U == 16) {      // chunk rows: 16 lanes at once
                vis[0] = row16(P + cv, edge ? 0 : step, M_CUBE_CAP);
                ch[0] = vis[0] & same16(P + cv);
            } else
#endif
            if (U <= 64) {      // one word
                ulong a = 0, e = 0;
                for (int u = 0; u < U; u++) {
                    a |= (ulong)(face_key(P, flags, cv + u, step, edge, F_CUBE | F_CAP) != 0) << u;
                    e |= (ulong)(u > 0 && P[cv + u] == P[cv + u - 1]) << u;
                }
                vis[0] = a; ch[0] = a & e;
            } else {
                for (int u = 0; u < U; u++) {
                    ulong bit = 1UL << (u & 63);
                    if (face_key(P, flags, cv + u, step, edge, F_CUBE | F_CAP)) vis[u >> 6] |= bit;
                    if (u > 0 && P[cv + u] == P[cv + u - 1]) ch[u >> 6] |= bit;
                }
                for (int w = 0; w < MW; w++) ch[w] &= vis[w];
            }
            if (!(vis[0] | vis[1] | vis[2] | vis[3]) && !o.nopen) continue;
        }
        row_step(&o, vis, ch, v, P + cv, 1, sink, t, d, s);
    }
}


// X and # planes of a cell with block b (none for other shapes).
inline void shapes(Sink *k, __constant uchar *flags, int t, int x, int y, int z, ushort b) {
    uint f = flags[b];
    if (f & F_X) { put(k, t, x, y, z, 6, 1, 1, b); put(k, t, x, y, z, 7, 1, 1, b); }
    if (f & F_HASH)
        for (int h = 8; h < 12; h++) put(k, t, x, y, z, h, 1, 1, b);
}

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
// The same greedy rows as `tile` (`row_step`) for one x/y slice's columns [ulo, uhi)
// along z: cell u at c0 + v * sv + u * su; runs chain only within [ulo, uhi).
inline void span_greedy(__global const ushort *P, __constant uchar *flags, long c0, long sv,
                        long su, long step, uint want, int V, int ulo, int uhi,
                        int t, int d, int s, Sink *sink) {
    Open o;
    open_init(&o);
    for (int v = 0; v <= V; v++) {
        ulong vis[MW] = {0, 0, 0, 0}, ch[MW] = {0, 0, 0, 0};
        long cv = c0 + (long)v * sv;
        if (v < V) {
            for (int u = ulo; u < uhi; u++) {
                ulong bit = 1UL << (u & 63);
                long c = cv + u * su;
                if (face_key(P, flags, c, step, false, want)) vis[u >> 6] |= bit;
                if (u > ulo && P[c] == P[c - su]) ch[u >> 6] |= bit;
            }
            for (int w = 0; w < MW; w++) ch[w] &= vis[w];
            if (!(vis[0] | vis[1] | vis[2] | vis[3]) && !o.nopen) continue;
        }
        row_step(&o, vis, ch, v, P + cv, su, sink, t, d, s);
    }
}

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
