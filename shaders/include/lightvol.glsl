// The light of the whole view in one camera-centred toroidal texture (no bindless
// textures needed): chunk (cx, cy) lives in layer (cx mod N) + N (cy mod N) of a 2D
// array of 256x256 layers, its voxel (x, y, z) at texel (x + 16 (z & 15), y + 16 (z >> 4))
// as the packed SPEC §3 uint16 in a 16-bit unorm (exact). A layer is one chunk, so a
// changed chunk is one layer's upload (or one draw where a device cannot write part of
// a texture). Outside the resident box [vol_lo, vol_hi) the light is open daylight.
// Sampling and eq. 4.1 are light.glsl's; this file only plugs the lookup into it
// (call light_sample(light_vol, vec3(0.0), p, n): voxel indices are world coordinates).
#include "include/frame.glsl"
//@ sampler sampler2DArray light_vol
// (frame.glsl: vol_n slots per side, the resident box [vol_lo, vol_hi) in blocks)

vec4 light_torus(sampler2DArray vol, ivec3 v) {
    uint l;
    if (v.z > 255) l = 0xF000u;
    else if (v.z < 0) l = 0u;
    else if (any(lessThan(v.xy, vol_lo)) || any(greaterThanEqual(v.xy, vol_hi))) l = 0xF000u;
    else {
        // GLSL leaves % of negative ints undefined; float floor and mod are exact here
        ivec2 c = ivec2(floor(vec2(v.xy) / 16.0));
        ivec2 s = ivec2(mod(vec2(c), float(vol_n)));
        ivec2 t = v.xy - 16 * c + 16 * ivec2(v.z & 15, v.z >> 4);
        l = uint(texelFetch(vol, ivec3(t, s.x + vol_n * s.y), 0).r * 65535.0 + 0.5);
    }
    return vec4(float(l & 15u), float((l >> 4) & 15u), float((l >> 8) & 15u), float(l >> 12)) / 15.0;
}

#define LIGHT_VOLUME sampler2DArray
#define LIGHT_FETCH(vol, i) light_torus(vol, i)
#include "include/light.glsl"
