// The shown area's outer wall where its meshes have none (render/walls.py: chunks
// meshed against their real neighbours, as the live view streams them): a camera ray
// that crosses the area's border below the top of the border column there meets a
// stone wall, entering the area from outside (a side view: no slab open into caves) or
// leaving it from inside (a cave that reaches the border ends in stone). The deferred
// pass shades it where nothing drawn is nearer. Frame members: walls, wall_layer.
#ifndef WALLS_GLSL
#define WALLS_GLSL
#include "include/eye.glsl"

//@ sampler sampler2DArray wall_tops  if !defined(LAYER)  // a row per side (x0, x1, y0, y1): column heights; + 4: top side layers, + 8: filler layers
//@ sampler sampler2DArray tex        if !defined(LAYER)  // the block textures (stone's layer: wall_layer)

// the height (top z + 1) of border column `along` (blocks from the area's low corner)
// of side `row`
float wall_top(int row, float along) {
    int i = int(floor(along));
    if (i < 0 || i >= textureSize(wall_tops, 0).x) return 0.0;
    return texelFetch(wall_tops, ivec3(i, row, 0), 0).r * 65535.0;
}

// The texture layer of the wall at p on side `row`: the top block's side for its top
// block, its filler (dirt under grass) for FILLER (render/walls.py) more, then stone
// (wall_layer), as the closed area's real faces show them.
int wall_texture(int row, vec3 p) {
    float along = row < 2 ? p.y - area_box.y : p.x - area_box.x;
    int i = clamp(int(floor(along)), 0, textureSize(wall_tops, 0).x - 1);
    float below = texelFetch(wall_tops, ivec3(i, row, 0), 0).r * 65535.0 - floor(p.z);
    int k = below <= 1.0 ? 4 : below <= 4.0 ? 8 : 0;
    if (k == 0) return wall_layer;
    int l = int(texelFetch(wall_tops, ivec3(i, row + k, 0), 0).r * 65535.0 + 0.5);
    return l > 0 ? l : wall_layer;
}

// Where the ray through uv meets the wall: the point (on the border plane), its normal
// towards the eye and its side; false where it does not.
bool wall_hit(vec2 uv, out vec3 p, out vec3 n, out int row) {
    p = vec3(0.0); n = vec3(0.0); row = 0;
    vec3 ro = ortho ? world_pos(inv_vp, uv, 0.0) : cam_pos;
    vec3 d = ray_dir(uv);
    vec2 dd = vec2(abs(d.x) < 1e-7 ? 1e-7 : d.x, abs(d.y) < 1e-7 ? 1e-7 : d.y);
    vec2 t0 = (area_box.xy - ro.xy) / dd, t1 = (area_box.zw - ro.xy) / dd;
    vec2 tn = min(t0, t1), tf = max(t0, t1);
    float t_in = max(tn.x, tn.y), t_out = min(tf.x, tf.y);
    if (t_in > t_out || t_out <= 0.0) return false;
    for (int k = 0; k < 2; k++) {  // entering from outside, then leaving
        float t = k == 0 ? t_in : t_out;
        if (t <= 0.0) continue;
        bool xs = k == 0 ? tn.x >= tn.y : tf.x <= tf.y;  // an x = const plane
        bool low = (k == 0) == (xs ? d.x > 0.0 : d.y > 0.0);  // the plane at area_box.xy
        p = ro + d * t;
        if (xs) p.x = low ? area_box.x : area_box.z;
        else p.y = low ? area_box.y : area_box.w;
        row = (xs ? 0 : 2) + (low ? 0 : 1);
        float along = xs ? p.y - area_box.y : p.x - area_box.x;
        if (p.z >= 0.0 && p.z < wall_top(row, along)) {
            float s = (xs ? d.x : d.y) > 0.0 ? -1.0 : 1.0;  // against the ray
            n = xs ? vec3(s, 0.0, 0.0) : vec3(0.0, s, 0.0);
            return true;
        }
    }
    return false;
}

// The wall's albedo: its block's texture (wall_texture) at the mip level of a pixel's size there (a
// perspective pixel's angle star_px times the distance; an orthographic one's size
// from the projection, uv and dy a pixel above it), as block.frag's texel() would pick
vec4 wall_albedo(vec3 p, int row, vec2 uv, float dy) {
    vec2 t = vec2(row < 2 ? p.y : p.x, p.z) * 16.0;
    float texels = 16.0 * (ortho ? distance(world_pos(inv_vp, uv + vec2(0.0, dy), 0.0),
                                            world_pos(inv_vp, uv, 0.0))
                                 : eye_dist(p) * star_px);
    int l = int(clamp(floor(log2(max(texels, 1.0)) + 0.5), 0.0, 4.0));
    int size = 16 >> l;
    ivec2 i = ivec2(floor(t / float(1 << l))) & (size - 1);
    return texelFetch(tex, ivec3(i.x + 32 - (32 >> l), i.y, wall_texture(row, p)), 0);
}
#endif
