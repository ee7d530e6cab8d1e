// G-buffer writer. Defines: ALPHA_TEST, PEEL (discard at/before the previous layer),
// SHADOW (depth only), DEBUG_AGG (colour by merged quad), SMOOTH_MAG (edge-aware
// magnification), MSAA_ALPHA (alpha test per sample), OIT (forward-shaded weighted
// blended order-independent transparency: accumulation instead of a G-buffer).
// Albedo stays sRGB-encoded as the textures are (8 bits hold it better; shade.glsl
// decodes it once per shaded sample, not per fragment of every overdrawn layer);
// water (glow_scale < 0 on its layers, render/pipeline.py) is marked by glow 1 (other
// glow stays below) and, as the nearest peeled layer, takes its colour and opacity
// from its depth.
#include "include/common.glsl"
#include "include/frame.glsl"
#ifdef OIT
#include "include/shade.glsl"
#endif

uniform sampler2DArray tex;
uniform sampler2DArray glow_tex;
uniform float glow_scale[64];
#ifdef PEEL
uniform GSAMPLER opaque_depth;
uniform GSAMPLER prev_depth;
#endif

#if defined(MSAA_ALPHA) && SAMPLES > 1
sample in vec2 g_uv;
#else
in vec2 g_uv;
#endif
in vec3 g_world;
flat in float g_layer;
flat in vec3 g_normal;
flat in uint g_quad;

#if defined(OIT)
layout(location = 0) out vec4 out_accum;   // sum of w * premultiplied colour, sum of w * alpha
layout(location = 1) out vec4 out_reveal;  // r: sum of -log(1 - alpha)
#elif !defined(SHADOW)
layout(location = 0) out vec4 out_albedo;
layout(location = 1) out vec4 out_normal;
#endif

vec4 texel(vec2 uv) {
#ifdef SMOOTH_MAG
    // Linear blend only across texel borders, as wide as one screen pixel (fig. 6.3).
    vec2 t = uv * 16.0;
    vec2 w = max(fwidth(t), vec2(1e-4));
    vec2 f = fract(t - 0.5);
    vec2 s = clamp((f - 0.5) / w + 0.5, 0.0, 1.0);
    vec2 q = (floor(t - 0.5) + s + 0.5) / 16.0;
    return textureGrad(tex, vec3(q, g_layer), dFdx(uv), dFdy(uv));
#else
    return texture(tex, vec3(uv, g_layer));
#endif
}

#ifdef OIT
// McGuire & Bavoil 2013 (JCGT 2(2)), eq. 6 with the weight of eq. 9:
//   w = alpha * clamp(0.03 / (1e-5 + (z / 200)^4), 1e-2, 3e3), z the view depth.
// Eq. 9 is made for depths of about 0.1..500 units, and ours are blocks (metres) up
// to the far edge of the area (~150-400): it separates layers a few blocks apart
// from ~10 blocks on. Eq. 10 uses the hyperbolic depth-buffer value instead; with
// near = 0.1 that is ~1 beyond a few blocks, so its weight sits at the 1e-2 floor and
// would not tell near from far. Both clamps fit RGBA16F (max 65504).
// Revealage prod(1 - alpha) is stored as sum(-log(1 - alpha)) so both attachments
// add (ONE, ONE): moderngl sets one blend function for all draw buffers (no
// glBlendFunci), both clear to 0 and the sum is as order-independent as the product.
void oit(vec4 c) {
    float a = min(c.a, 0.999);  // alpha 1 would be -log(0)
    if (a <= 0.0) discard;
    float z = 1.0 / gl_FragCoord.w;  // perspective: w_clip is the view depth
    float w = a * clamp(0.03 / (1e-5 + pow(z / 200.0, 4.0)), 1e-2, 3e3);
    out_accum = vec4(c.rgb, a) * w;
    out_reveal = vec4(-log(1.0 - a), 0.0, 0.0, 0.0);
}
#endif

// Water over `s` blocks of depth (to the opaque floor): more of its own colour and
// less of the floor the deeper it is (Beer-Lambert, one grey transmittance). The
// factors are on linear light; c is encoded, so they are too (^(1/2.2)).
vec4 water_body(vec4 c, float s) {
    float k = 1.0 - exp(-s * 0.25);
    vec3 f = mix(vec3(0.5, 0.6, 0.5), vec3(0.08, 0.2, 0.16), k);
    return vec4(c.rgb * pow(f, vec3(1.0 / 2.2)), mix(0.3, 0.95, k));
}

void main() {
#ifdef PEEL
    // behind the opaque scene, or not behind the previous layer: not this layer's
    ivec2 pc = ivec2(gl_FragCoord.xy);
    if (gl_FragCoord.z >= FETCH(opaque_depth, pc, gl_SampleID).r) discard;
#if PEEL > 1
    if (gl_FragCoord.z <= FETCH(prev_depth, pc, gl_SampleID).r + 1e-7) discard;
#endif
#endif
    vec4 c = texel(g_uv);
#ifdef ALPHA_TEST
    if (c.a < 0.5) discard;
    c.a = 1.0;
#endif
#ifndef SHADOW
    vec3 n = gl_FrontFacing ? g_normal : -g_normal;  // double-sided passes
    float scale = glow_scale[int(g_layer)];
    float glow = scale < 0.0 ? 1.0 : min(texture(glow_tex, vec3(g_uv, g_layer)).r * scale, 0.99);
#if defined(PEEL) && PEEL == 1
    if (scale < 0.0 && water_fx) {
        float d = FETCH(opaque_depth, pc, gl_SampleID).r;
        vec2 uv = gl_FragCoord.xy / vec2(textureSize(opaque_depth MS_ARG));
        c = water_body(c, d < 1.0 ? distance(g_world, world_pos(inv_vp, uv, d)) : 64.0);
    }
#endif
#ifdef DEBUG_AGG
    c.rgb = hash_color(g_quad * 7919u + uint(g_layer));  // one colour per merged quad
    glow = 0.0;
#endif
#ifdef OIT
    oit(shade_surface(c, g_world, n, glow));
#else
    out_albedo = c;
    out_normal = vec4(n * 0.5 + 0.5, glow);
#endif
#endif
}
