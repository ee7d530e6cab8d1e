// Far terrain (issue 22): a far tile's heightfield into the G-buffer, like the near
// chunks (render/far.py draws it after them). The vertex is voxel_addon/far/mesh.py's
// 12 bytes: in_f.x kx (bits 0-5), ky (6-11), z in 1/8 blocks (12-24), kind (25-26:
// ground, water, skirt); in_f.y normal x, y (int8 each) and albedo RGB565 (16-31);
// in_f.z zc, the z of the next coarser level's surface (geomorphing: no popping).
// The depth range is split (far.py): gl_Position by the far projection (far_vp).
#include "include/frame.glsl"

//@ in uvec3 in_f
//@ push vec4 tile         // xy: the tile's vertex (0, 0) minus 0.5, z: spacing (blocks)
//@ push vec4 morph        // k = smoothstep of clamp(d * x - y): far/grid.py morph(); x 0: none
//@ push mat4 far_vp       // the far projection, its depth in [0.5, 1]
//@ push vec4 near_box     // the chunks' box (far.frag): xy its first chunk, zw its size
//@ vary smooth vec3 f_world
//@ vary smooth vec3 f_normal
//@ vary smooth vec3 f_albedo
//@ vary flat float f_water  // 1: a water surface (block.frag's mark: glow 1)
//@ vary smooth vec4 f_body   // water: rgb its own colour (sRGB), a the depth to its floor
//@ vary smooth vec2 f_under  // ground under water: (its water face's z, 1) where it has water

void main() {
    uint w0 = in_f.x, w1 = in_f.y;
    vec2 xy = tile.xy + vec2(float(w0 & 63u), float((w0 >> 6) & 63u)) * tile.z + 0.5;
    float z = float((w0 >> 12) & 8191u) / 8.0;
    float zc = float(in_f.z & 8191u) / 8.0;
    float t = clamp(distance(xy, cam_pos.xy) * morph.x - morph.y, 0.0, 1.0);
    z = mix(z, zc, t * t * (3.0 - 2.0 * t));
    // Under the chunks (where far.frag drops it) the ground goes down to the bottom:
    // the cells across the chunks' edge become a wall behind it. Else a ray passing
    // just over the edge could cross the far surface (coarser, raised by canopies)
    // under the chunks, be dropped there and miss the ground behind (a gap at the
    // seam). Not the water, nor a floor under shallow water (up to 2 blocks; word 2
    // bits 13-21, far/mesh.py): the wall's slope, just outside the edge, was the floor
    // that the near water by the edge saw through it: a deep blue line along the
    // seam by every beach (a ray under such water meeting a floor rising at the edge
    // now finds nothing behind it: spots, drawn as deep water as the wall drew them).
    vec2 cc = floor(xy / 16.0) - near_box.xy;
    bool water = ((w0 >> 25) & 3u) == 1u;
    uint wl = water ? 0u : (in_f.z >> 13) & 511u;  // the water over a ground vertex (+1)
    if (!water && all(greaterThanEqual(cc, vec2(0.0))) && all(lessThan(cc, near_box.zw)))
        z = wl == 0u || float(wl) - z > 2.5 ? -16.0 : z;
    f_under = wl != 0u ? vec2(float(wl), 1.0) : vec2(0.0);
    int nx = int(w1 & 255u), ny = int((w1 >> 8) & 255u);  // int8, two's complement
    vec2 n = vec2(float(nx >= 128 ? nx - 256 : nx), float(ny >= 128 ? ny - 256 : ny)) / 127.0;
    uint c = w1 >> 16;
    f_albedo = vec3(float(c >> 11) / 31.0, float((c >> 5) & 63u) / 63.0, float(c & 31u) / 31.0);
    f_water = ((w0 >> 25) & 3u) == 1u ? 1.0 : 0.0;
    f_body = vec4(0.0);
    if (f_water > 0.5) {  // (far/mesh.py: the floor's colour lit under it, its depth)
        f_albedo = vec3(float(w1 & 255u), float((w1 >> 8) & 255u), float((w1 >> 16) & 255u)) / 255.0;
        uint o = in_f.z >> 16;
        f_body = vec4(float(o >> 11) / 31.0, float((o >> 5) & 63u) / 63.0, float(o & 31u) / 31.0,
                      float(w1 >> 24) / 8.0);
        n = vec2(0.0);
    }
    f_normal = vec3(n, sqrt(max(0.0, 1.0 - dot(n, n))));
    f_world = vec3(xy, z);
    gl_Position = far_vp * vec4(f_world, 1.0);
}
