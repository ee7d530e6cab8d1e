// G-buffer writer. Defines: ALPHA_TEST, PEEL (discard at/before the previous layer),
// SHADOW (depth only), DEBUG_AGG (colour by merged quad), MSAA_ALPHA (alpha test per
// sample), OIT (forward-shaded weighted blended order-independent transparency:
// accumulation instead of a G-buffer). (SMOOTH_MAG, the edge-aware magnification of
// fig. 6.3, moved texel borders under a nearest magnification filter, which made it
// the nearest texel again: it had no visible effect and is not applied here.)
// Albedo stays sRGB-encoded as the textures are (8 bits hold it better; shade.glsl
// decodes it once per shaded sample, not per fragment of every overdrawn layer);
// water (its glow texels are 1, render/blocktex.py; other glow stays below) is marked
// by glow 1 and, as the nearest peeled layer, takes its colour and opacity from its depth.
// ZCOPY (a one-sample peel layer): its depth also into a colour target, which the
// layer's lighting reads while its depth buffer keeps that pass to covered pixels.
#include "include/common.glsl"
#include "include/frame.glsl"
#include "include/eye.glsl"
#ifdef OIT
#include "include/shade.glsl"
#endif

//@ sampler sampler2DArray tex       // per layer the mip chain side by side (texel())
//@ sampler sampler2DArray mc_tex    if MODEL  // the resource stack's sprites, laid out as tex
//@ sampler sampler2DArray glow_tex  // 16x16 per layer: the mask times its blocks' glow
//@ sampler sampler2D palette        // the world's colours, 256 a row (`color` blocks)
//@ sampler gdepth2D opaque_depth   if PEEL
//@ sampler gdepth2D prev_depth     if PEEL
//@ sampler gsampler2D opaque_normal if defined(PEEL) && PEEL == 1  // a: the water mark (far water)
//@ out 0 vec4 out_accum            if OIT  // sum of w * premultiplied colour, sum of w * alpha
//@ out 1 vec4 out_reveal           if OIT  // r: sum of -log(1 - alpha)
//@ out 0 vec4 out_albedo           if !defined(OIT) && !defined(SHADOW)
//@ out 1 vec4 out_normal           if !defined(OIT) && !defined(SHADOW)
//@ out 2 vec4 out_depth            if ZCOPY  // (peel, one sample) its depth: read where it is bound

// Texels with no sampler state (Blender's gpu module binds textures nearest, clamped,
// without mipmaps): a layer holds the 16x16 texture and its mip levels side by side
// (level l, 16 >> l wide, at x = 32 - (32 >> l)); the texel index wraps (merged quads
// repeat the texture), and GL's NEAREST_MIPMAP_LINEAR is done here: the level from the
// derivatives, the nearest texel in the two levels around it, blended.
#ifdef MODEL
#define SPRITES mc_tex
#else
#define SPRITES tex
#endif
vec4 level_texel(vec2 t, int l) {  // t: level-0 texel coordinates
    int size = 16 >> l;
    ivec2 i = ivec2(floor(t / float(1 << l))) & (size - 1);  // (two's complement: wraps)
    return texelFetch(SPRITES, ivec3(i.x + 32 - (32 >> l), i.y, int(g_layer)), 0);
}

vec4 texel(vec2 uv) {
    vec2 t = uv * 16.0;
#ifdef SHADOW
    return level_texel(t, 0);  // casters: the alpha test of the texture itself
#endif
    vec2 dx = dFdx(t), dy = dFdy(t);
    float lod = 0.5 * log2(max(dot(dx, dx), dot(dy, dy)));  // GL's: log2 of the longer
    if (!(lod > 0.0)) return level_texel(t, 0);  // magnified (or a degenerate derivative)
    lod = min(lod, 4.0);
    int l = min(int(lod), 3);
    return mix(level_texel(t, l), level_texel(t, l + 1), lod - float(l));
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
#ifdef MODEL
    c.rgb *= g_tint;  // (the game multiplies the encoded colour)
#endif
    if (g_color != 0u)  // a `color` block: its texture tinted by the palette colour
        c.rgb *= texelFetch(palette, ivec2(int(g_color & 255u), int(g_color >> 8)), 0).rgb;
#ifndef SHADOW
    vec3 n = gl_FrontFacing ? g_normal : -g_normal;  // double-sided passes
    ivec2 gi = ivec2(floor(g_uv * 16.0)) & 15;  // nearest, repeated
#ifdef MODEL
    float glow = 0.0;  // (its block's light is in the light volume)
#else
    float glow = texelFetch(glow_tex, ivec3(gi, int(g_layer)), 0).r;  // (mask x block glow)
#endif
#if defined(PEEL) && PEEL == 1
    if (glow > 0.999) {  // water (blocktex.py's mark), the nearest layer
        float d = FETCH(opaque_depth, pc, gl_SampleID).r;
        vec2 uv = gl_FragCoord.xy / vec2(textureSize(opaque_depth MS_ARG));
        float s = d < 1.0 ? distance(g_world, scene_pos(uv, d)) : 64.0;
        // Far water right behind it (the only water in the opaque layer): the chunks'
        // edge, where far.frag keeps a far pixel a twentieth of a block inside (else a
        // crack). The far water there is this water, coloured over its own floor; taken
        // as this water's floor at depth 0 it was a shallow, lighter pixel: a dotted
        // trace along the near/far seam in deep water, seen from high up (issue 28).
        if (s < 0.5 && FETCH(opaque_normal, pc, gl_SampleID).a > 0.999) discard;
        if (water_fx) c = water_body(c, s);
    }
#endif
#ifdef DEBUG_AGG
    c.rgb = hash_color(g_quad * 7919u + uint(g_layer));  // one colour per merged quad
    glow = 0.0;
#endif
#ifdef OIT
    oit(shade_surface(c, g_world, n, glow, 1.0));
#else
    out_albedo = c;
    out_normal = vec4(n * 0.5 + 0.5, glow);
#ifdef ZCOPY
    out_depth = vec4(gl_FragCoord.z);
#endif
#endif
#endif
}
