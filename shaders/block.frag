// G-buffer writer. Defines: ALPHA_TEST, PEEL (discard at/before the previous layer),
// SHADOW (depth only), DEBUG_AGG (colour by merged quad), SMOOTH_MAG (edge-aware
// magnification), MSAA_ALPHA (alpha test per sample).
#include "include/common.glsl"

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

#ifndef SHADOW
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
    float glow = texture(glow_tex, vec3(g_uv, g_layer)).r * glow_scale[int(g_layer)];
#ifdef DEBUG_AGG
    c.rgb = hash_color(g_quad * 7919u + uint(g_layer));  // one colour per merged quad
    glow = 0.0;
#endif
    out_albedo = c;
    out_normal = vec4(n * 0.5 + 0.5, glow);
#endif
}
