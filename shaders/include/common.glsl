// Shared helpers. SAMPLES > 1 means G-buffer textures are multisampled.
#ifndef SAMPLES
#define SAMPLES 1
#endif
#if SAMPLES > 1
#define GSAMPLER sampler2DMS
#define FETCH(t, p, s) texelFetch(t, p, s)
#define MS_ARG
#else
#define GSAMPLER sampler2D
#define FETCH(t, p, s) texelFetch(t, p, 0)
#define MS_ARG , 0
#endif

vec3 hash_color(uint h) {
    h = (h ^ 61u) ^ (h >> 16); h *= 9u; h ^= h >> 4; h *= 0x27d4eb2du; h ^= h >> 15;
    return vec3(float(h & 255u), float((h >> 8) & 255u), float((h >> 16) & 255u)) / 255.0;
}

// Linear filtering by hand (devices bind textures nearest): four texels, clamped.
vec4 bilinear(sampler2D t, vec2 uv) {
    ivec2 size = textureSize(t, 0);
    vec2 p = uv * vec2(size) - 0.5;
    ivec2 b = ivec2(floor(p));
    vec2 f = p - floor(p);
    ivec2 hi = size - 1;
    vec4 a = mix(texelFetch(t, clamp(b, ivec2(0), hi), 0),
                 texelFetch(t, clamp(b + ivec2(1, 0), ivec2(0), hi), 0), f.x);
    vec4 c = mix(texelFetch(t, clamp(b + ivec2(0, 1), ivec2(0), hi), 0),
                 texelFetch(t, clamp(b + ivec2(1, 1), ivec2(0), hi), 0), f.x);
    return mix(a, c, f.y);
}

// Display colours into a host's framebuffer: Blender's viewport framebuffer is sRGB
// (the GPU encodes what is written), and Blender sets its builtin `srgbTarget` then (a
// `//@ push int srgbTarget` is filled by Blender, 0 elsewhere): decode ours first, as
// Blender's own shaders do (blender_srgb_to_framebuffer_space).
vec3 to_target(vec3 c, int srgb) {
    if (srgb == 0) return c;
    c = clamp(c, 0.0, 1.0);
    // the curve above its linear toe, ((c + 0.055) / 1.055)^2.4, as a quartic: within
    // 0.12/255 of it once the target encodes again (every 8-bit value comes back the
    // same), without the pow per channel that cost a full-region pass 3-6 ms on
    // llvmpipe (issue 28)
    vec3 p = 0.00113835 + c * (0.02658994 + c * (0.56907264 + c * (0.51302564 - 0.11046849 * c)));
    return mix(c / 12.92, p, step(vec3(0.04045), c));
}

// linear -> sRGB display values (a target that does not encode what is written)
vec3 srgb_encode(vec3 c) {
    c = max(c, vec3(0.0));
    return mix(c * 12.92, 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, step(vec3(0.0031308), c));
}

// World position of a depth-buffer value at normalised screen coordinate uv.
vec3 world_pos(mat4 inv_m, vec2 uv, float depth) {
    vec4 p = inv_m * vec4(uv * 2.0 - 1.0, depth * 2.0 - 1.0, 1.0);
    return p.xyz / p.w;
}
