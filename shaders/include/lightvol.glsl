// The light of the whole view in one camera-centred toroidal 3D texture (no bindless
// textures needed): voxel (x, y, z) lives at texel (x mod S, y mod S, z) as the packed
// SPEC §3 uint16. Outside the resident box [vol_lo, vol_hi) the light is open daylight.
// Sampling and eq. 4.1 are light.glsl's; this file only plugs the lookup into it
// (call light_sample(light_vol, vec3(0.0), p, n): voxel indices are world coordinates).
//@ sampler usampler3D light_vol
//@ push int vol_size
//@ push ivec2 vol_lo
//@ push ivec2 vol_hi

vec4 light_torus(usampler3D vol, ivec3 v) {
    uint l;
    if (v.z > 255) l = 0xF000u;
    else if (v.z < 0) l = 0u;
    else if (any(lessThan(v.xy, vol_lo)) || any(greaterThanEqual(v.xy, vol_hi))) l = 0xF000u;
    // GLSL leaves % of negative ints undefined; float mod floors (exact below 2^24)
    else l = texelFetch(vol, ivec3(ivec2(mod(vec2(v.xy), float(vol_size))), v.z), 0).r;
    return vec4(float(l & 15u), float((l >> 4) & 15u), float((l >> 8) & 15u), float(l >> 12)) / 15.0;
}

#define LIGHT_VOLUME usampler3D
#define LIGHT_FETCH(vol, i) light_torus(vol, i)
#include "include/light.glsl"
