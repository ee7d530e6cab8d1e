// Decoder of the packed meshing vertex (voxel_addon/meshing/vertex.py, README.md):
// one uint per vertex; bits 0-4 x, 5-9 y, 10-16 z (region-local corner, 0..16/16/64),
// 17-20 face code, 21-26 texture layer, 27-28 animation, 29-31 # inset (1/16).
// Face codes: 0..5 cube -x +x -y +y -z +z; 6, 7 X planes; 8..11 # planes (sides 0..3
// moved inward by the inset). UVs are in voxel units and tile (REPEAT) across merged
// quads; v grows with +z on side faces.

struct Vertex {
    vec3 position;  // region-local; add the region origin (chunk*16, chunk*16, region*height)
    vec3 normal;    // front side; double-sided passes flip it with gl_FrontFacing
    vec2 uv;
    uint layer;
    uint face;
    uint anim;      // core.blocks.ANIMATIONS: 0 none, 1 wave_top, 2 wave, 3 water
};

Vertex decode(uint v) {
    // (tables inside the function: Metal has no global arrays of GLSL's kind)
    const vec3 V_NORMALS[12] = vec3[12](
        vec3(-1.0, 0.0, 0.0), vec3(1.0, 0.0, 0.0), vec3(0.0, -1.0, 0.0), vec3(0.0, 1.0, 0.0),
        vec3(0.0, 0.0, -1.0), vec3(0.0, 0.0, 1.0),
        vec3(0.70710678, -0.70710678, 0.0), vec3(0.70710678, 0.70710678, 0.0),
        vec3(-1.0, 0.0, 0.0), vec3(1.0, 0.0, 0.0), vec3(0.0, -1.0, 0.0), vec3(0.0, 1.0, 0.0));
    const vec3 V_UV_U[12] = vec3[12](
        vec3(0.0, -1.0, 0.0), vec3(0.0, 1.0, 0.0), vec3(1.0, 0.0, 0.0), vec3(-1.0, 0.0, 0.0),
        vec3(1.0, 0.0, 0.0), vec3(1.0, 0.0, 0.0), vec3(1.0, 0.0, 0.0), vec3(0.0, 1.0, 0.0),
        vec3(0.0, -1.0, 0.0), vec3(0.0, 1.0, 0.0), vec3(1.0, 0.0, 0.0), vec3(-1.0, 0.0, 0.0));
    const vec3 V_UV_V[12] = vec3[12](
        vec3(0.0, 0.0, 1.0), vec3(0.0, 0.0, 1.0), vec3(0.0, 0.0, 1.0), vec3(0.0, 0.0, 1.0),
        vec3(0.0, -1.0, 0.0), vec3(0.0, 1.0, 0.0),
        vec3(0.0, 0.0, 1.0), vec3(0.0, 0.0, 1.0), vec3(0.0, 0.0, 1.0), vec3(0.0, 0.0, 1.0),
        vec3(0.0, 0.0, 1.0), vec3(0.0, 0.0, 1.0));
    Vertex o;
    o.face = (v >> 17) & 15u;
    o.layer = (v >> 21) & 63u;
    o.anim = (v >> 27) & 3u;
    vec3 p = vec3(float(v & 31u), float((v >> 5) & 31u), float((v >> 10) & 127u));
    // uv from the grid corner: the # inset is a shift along the normal, it does not move uv
    o.uv = vec2(dot(p, V_UV_U[o.face]), dot(p, V_UV_V[o.face]));
    o.normal = V_NORMALS[o.face];
    if (o.face >= 8u) p -= o.normal * (float(v >> 29) / 16.0);
    o.position = p;
    return o;
}
