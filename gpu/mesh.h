// Shared by the meshing kernels (voxel_addon/meshing/cl.py). The block area P is
// (PW, PH, 256) ushort, x fastest, with a one-voxel ring around the meshed window;
// below z=0 and above z=255 is air. Tiles (chunks) of TW x TH cells are meshed apart.
#ifndef MESH_H
#define MESH_H

// Block flag bits (meshing.faces.tables)
#define F_CUBE 1u
#define F_OPAQUE 2u
#define F_SAME_HIDES 4u
#define F_CAP 8u
#define F_X 16u
#define F_HASH 32u

// Key of the face of cell c toward c + step: its block id when the face is emitted,
// else 0. `want` is F_CUBE for side faces, F_CUBE | F_CAP for -z/+z; `edge`: the
// neighbour is outside the world (air). With FLAG_MASKS (all ids < 64, set by
// meshing/cl.py) the flag tests are bit tests on constants instead of table loads.
#ifdef FLAG_MASKS
#define HAS(m, id) ((((ulong)(m)) >> (id)) & 1UL)
inline bool is_opaque(__constant uchar *F, ushort a) { return HAS(M_OPAQUE, a); }
inline ushort face_key(__global const ushort *P, __constant uchar *F, long c, long step,
                       bool edge, uint want) {
    ushort a = P[c];
    if (!HAS(want == F_CUBE ? M_CUBE : M_CUBE_CAP, a)) return 0;
    ushort b = edge ? (ushort)0 : P[c + step];
    return (HAS(M_OPAQUE, b) || (HAS(M_SAME, a) && a == b)) ? (ushort)0 : a;
}
#else
inline bool is_opaque(__constant uchar *F, ushort a) { return (F[a] & F_OPAQUE) != 0; }
inline ushort face_key(__global const ushort *P, __constant uchar *F, long c, long step,
                       bool edge, uint want) {
    ushort a = P[c];
    uint fa = F[a];
    if (!(fa & want)) return 0;
    ushort b = edge ? (ushort)0 : P[c + step];
    uint fb = F[b];
    return ((fb & F_OPAQUE) || ((fa & F_SAME_HIDES) && a == b)) ? (ushort)0 : a;
}
#endif

#endif
