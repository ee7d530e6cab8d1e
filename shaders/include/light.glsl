// Light volume sampling (thesis §4.3, fig. 4.4-4.6) and eq. 4.1 shading.
// Twin of voxel_addon/light/sampler.py (the reference; tests compare the two).
//
// Light volume contract (the renderer owns the upload):
//   sampler3D `vol` of size (W, H, Z); texel (x, y, z) holds voxel
//   (origin + (x, y, z)) as RGBA = (R, G, B, D) / 15, i.e. the packed SPEC §3 light
//   unpacked and normalized (e.g. RGBA8 UNORM of level*17, or float level/15).
//   Only texelFetch is used, so any filter mode works.
//   `origin` is the world position of texel (0, 0, 0)'s voxel corner.
//   Other layouts define LIGHT_VOLUME (the sampler type) and LIGHT_FETCH(vol, i) ->
//   vec4 (R, G, B, D) in 0..1 of voxel index i (relative to origin, unclamped) before
//   including this file (the renderer's own volume: include/lightvol.glsl).
//
// light_sample(vol, origin, p, n): world point p on a face with unit normal n ->
//   vec4 (R, G, B, D) in 0..1: offset half a voxel along n, then trilinear
//   interpolation between the 8 nearest voxel centres (indices clamp to the volume).
// light_shade(albedo, rgb, glow, day, n, dl): eq. 4.1 with DayLight uniforms taken
//   from voxel_addon.light.daytime.DayParams (ambient, direct, light_dir, u).
#ifndef LIGHT_GLSL
#define LIGHT_GLSL

#ifndef LIGHT_FETCH
#define LIGHT_VOLUME sampler3D
#define LIGHT_FETCH(vol, i) texelFetch(vol, clamp(i, ivec3(0), textureSize(vol, 0) - 1), 0)
#endif

struct DayLight {
    vec3 ambient;    // DayParams.ambient
    vec3 direct;     // DayParams.direct
    vec3 light_dir;  // DayParams.light_dir (towards the sun by day, the moon by night)
    float u;         // DayParams.u, artificial light reduction (0..0.8)
};

vec4 light_sample(LIGHT_VOLUME vol, vec3 origin, vec3 p, vec3 n) {
    vec3 q = p + 0.5 * n - origin - 0.5;
    vec3 b = floor(q);
    vec3 f = q - b;
    ivec3 i0 = ivec3(b);
    vec4 acc = vec4(0.0);
    for (int k = 0; k < 8; k++) {
        ivec3 d = ivec3(k & 1, (k >> 1) & 1, (k >> 2) & 1);
        vec3 w3 = mix(1.0 - f, f, vec3(d));
        acc += w3.x * w3.y * w3.z * LIGHT_FETCH(vol, i0 + d);
    }
    return acc;
}

vec3 light_shade(vec3 albedo, vec3 rgb, float glow, float day, vec3 n, DayLight dl) {
    vec3 sky = dl.ambient + max(0.0, dot(n, dl.light_dir)) * dl.direct;
    return albedo * ((rgb + glow) * (1.0 - dl.u * day) + day * sky);
}

#endif
