// Shared by the greedy kernels of mesh_greedy.cl (`tile`, `slices`): where quads go
// (`Sink`), unit faces (`span`) and the greedy on bit rows (`row_step`, a z slice
// `span_z`, an x/y slice along z `span_greedy`).
//
// Slice views as meshing/faces.py: axis x -> (s, v, u) = (x, y, z); axis y -> (y, x, z);
// axis z -> (z, y, x). Greedy is Mikola's scan order run row by row: open rectangles
// continue while the whole row under them has their key; free cells start maximal
// runs. This needs only per-column state (private arrays of UMAX), not a seen mask;
// rows are bit masks (`row_step`), at most 256 columns.
#ifndef MESH_ROWS_H
#define MESH_ROWS_H
#include "mesh.h"

#define UMAX 256

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

// ---- greedy on bit masks (`tile` and `slices`) ------------------------------------
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

#endif
