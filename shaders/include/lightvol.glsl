// The light of the whole view in one camera-centred toroidal texture (no bindless
// textures needed): chunk (cx, cy) lives in layer (cx mod N) + N (cy mod N) of a 2D
// array of 256x256 layers, its voxel (x, y, z) at texel (x + 16 (z & 15), y + 16 (z >> 4))
// as the packed SPEC §3 uint16 in a 16-bit unorm (exact). A layer is one chunk, so a
// changed chunk is one layer's upload (or one draw where a device cannot write part of
// a texture). Outside the resident box [vol_lo, vol_hi) the light is open daylight.
// light_volume(p, n, spare) is light.glsl's light_sample for this volume (the
// reference and the equation 4.1 shading are light.glsl's), with each of the four
// voxel columns' addresses worked out once for its two voxels.
#include "include/frame.glsl"
#include "include/light.glsl"
//@ sampler sampler2DArray light_vol
// (frame.glsl: vol_n slots per side, the resident box [vol_lo, vol_hi) in blocks)

vec4 unpack_light(uint l) {
    return vec4(float(l & 15u), float((l >> 4) & 15u), float((l >> 8) & 15u), float(l >> 12)) / 15.0;
}

// voxel z of a resident column: its layer and texel (x, y) in the chunk's tile
uint light_voxel(ivec2 t, int layer, int z) {
    if (z > 255) return 0xF000u;  // above the world: open daylight
    if (z < 0) return 0u;
    return uint(texelFetch(light_vol, ivec3(t + 16 * ivec2(z & 15, z >> 4), layer), 0).r * 65535.0 + 0.5);
}

// World point p on a face with unit normal n -> vec4 (R, G, B, D) in 0..1: offset half
// a voxel along n, then trilinear between the 8 nearest voxel centres. spare: how far
// (blocks) outside the resident box p still counts as inside it (see below).
vec4 light_volume(vec3 p, vec3 n, float spare) {
    vec3 q = p + 0.5 * n - 0.5;
    vec3 b = floor(q);
    vec3 f = q - b;
    ivec3 i0 = ivec3(b);
    vec4 acc = vec4(0.0);
    // a point inside the box takes its columns from the box: the last half voxel by
    // its edge does not blend in open daylight (by a chunks' edge under water, the
    // floor's last half block lit as dry land: a bright line along the far seam).
    // With `spare` blocks to spare for the chunks' own surfaces (deferred.frag: a
    // block; not far terrain's, which starts at the edge and is lit as open land): a
    // position read back from the depth buffer lies off the surface (a few hundredths
    // along the view ray; under MSAA each sample's depth is read back on the pixel
    // centre's ray, up to half a pixel away), and the floor's last column under deep
    // water came back a hair outside, lit as dry land: bright dots along the chunks'
    // edge, seen through the water from high up (issue 28). (The box holds the
    // camera's chunk, so a chunk's surface seen just outside it is rare; its edge
    // column's light suits it better than open daylight anyway.)
    bool inside = all(greaterThanEqual(p.xy, vec2(vol_lo) - spare))
               && all(lessThan(p.xy, vec2(vol_hi) + spare));
    for (int k = 0; k < 4; k++) {
        ivec2 d = ivec2(k & 1, k >> 1);
        ivec2 v = i0.xy + d;
        if (inside) v = clamp(v, vol_lo, vol_hi - 1);
        vec2 w = mix(1.0 - f.xy, f.xy, vec2(d));
        uint l0, l1;
        if (any(lessThan(v, vol_lo)) || any(greaterThanEqual(v, vol_hi))) {
            l0 = i0.z < 0 ? 0u : 0xF000u;  // outside the window: open daylight
            l1 = i0.z + 1 < 0 ? 0u : 0xF000u;
        } else {
            // GLSL leaves % of negative ints undefined; float floor and mod are exact here
            ivec2 c = ivec2(floor(vec2(v) / 16.0));
            ivec2 s = ivec2(mod(vec2(c), float(vol_n)));
            int layer = s.x + vol_n * s.y;
            ivec2 t = v - 16 * c;
            l0 = light_voxel(t, layer, i0.z);
            l1 = light_voxel(t, layer, i0.z + 1);
        }
        acc += w.x * w.y * mix(unpack_light(l0), unpack_light(l1), f.z);
    }
    return acc;
}
