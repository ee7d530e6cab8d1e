// Deferred light for one layer (opaque or a depth-peeling layer), thesis §5.4:
// world position from depth, light volume + eq. 4.1 (include/light.glsl through
// include/lightvol.glsl), sun/moon shadow map, fog.
// Defines: SAMPLES, PER_SAMPLE, SHADOWS, LAYER (peel layer: premultiplied alpha
// out), FOG, FILL_HOLES (T-junction holes), DEBUG (1 albedo, 2 normal, 3 depth,
// 4 light, 5 aggregation).
#include "include/common.glsl"
#include "include/lightvol.glsl"
#include "include/sky.glsl"

uniform GSAMPLER g_depth;
uniform GSAMPLER g_albedo;
uniform GSAMPLER g_normal;
#ifdef SHADOWS
uniform sampler2DShadow shadow_map;
#endif

in vec2 v_uv;
layout(location = 0) out vec4 out_color;
#ifndef LAYER
layout(location = 1) out vec4 out_front;  // distance, normal: for SSAO, DOF, god rays
#endif

float shadow_at(vec3 p, vec3 n) {
#ifdef SHADOWS
    // linear fade by camera-to-fragment distance, none from shadow_fade on (§5.4.1)
    float dist = distance(p, shadow_eye);
    if (dist >= shadow_fade) return 1.0;
    // normal offset + slope bias against acne (fig. 5.17)
    vec3 q = p + n * (0.04 + 1.5 * shadow_texel);
    vec4 s = shadow_mat * vec4(q, 1.0);
    s.xyz /= s.w;
    if (any(lessThan(s.xy, vec2(0.0))) || any(greaterThan(s.xy, vec2(1.0)))) return 1.0;
    float ref = s.z - shadow_bias;
    // 2x2 PCF in one gather, bilinearly weighted (§5.4.1)
    vec2 size = vec2(textureSize(shadow_map, 0));
    vec2 t = s.xy * size - 0.5;
    vec2 f = fract(t);
    vec4 g = textureGather(shadow_map, (floor(t) + 1.0) / size, ref);
    float lit = mix(mix(g.w, g.z, f.x), mix(g.x, g.y, f.x), f.y);
    return mix(lit, 1.0, clamp(dist / shadow_fade, 0.0, 1.0));
#else
    return 1.0;
#endif
}

// Eq. 4.1 (light.glsl) with the direct term dimmed by the shadow map.
vec3 shade_light(vec3 albedo, vec3 p, vec3 n, float glow) {
    vec4 l = light_sample(light_vol, vec3(0.0), p, n);
    DayLight dl = DayLight(day_ambient, day_direct * shadow_at(p, n), sky_light_dir, day_u);
    return light_shade(albedo, l.rgb, glow, l.a, n, dl);
}

struct Frag { float depth; vec4 albedo; vec3 n; float glow; };

Frag fetch(ivec2 c, int s) {
    Frag f;
    f.depth = FETCH(g_depth, c, s).r;
    f.albedo = FETCH(g_albedo, c, s);
    vec4 nn = FETCH(g_normal, c, s);
    f.n = nn.xyz * 2.0 - 1.0;
    f.glow = nn.a;
    return f;
}

vec4 shade(Frag f, vec2 uv, out float dist) {
    vec3 p = world_pos(inv_vp, uv, f.depth);
    dist = length(p - cam_pos);
    vec3 n = normalize(f.n);
#if DEBUG == 1 || DEBUG == 5
    return vec4(f.albedo.rgb, 1.0) * f.albedo.a;
#elif DEBUG == 2
    return vec4(n * 0.5 + 0.5, 1.0) * f.albedo.a;
#elif DEBUG == 3
    return vec4(vec3(1.0 - pow(clamp(dist / far_dist, 0.0, 1.0), 0.5)), 1.0) * f.albedo.a;
#else
#if DEBUG == 4
    vec3 c = shade_light(vec3(1.0), p, n, f.glow);
#else
    vec3 c = shade_light(f.albedo.rgb, p, n, f.glow);
#endif
#ifdef FOG
    // horizontal distance: the area ends sideways, a high camera looking down sees clearly
    float k = clamp((length(p.xy - cam_pos.xy) - fog_start) / max(fog_end - fog_start, 1e-3),
                    0.0, 1.0);
    c = mix(c, sky_base(normalize(p - cam_pos)), k * k);
#endif
    return vec4(c * f.albedo.a, f.albedo.a);
#endif
}

void main() {
    ivec2 c = ivec2(gl_FragCoord.xy);
    vec2 px = 1.0 / vec2(textureSize(g_depth MS_ARG));
    vec4 acc = vec4(0.0);
    float dmin = 1e9;
    vec3 nsum = vec3(0.0);
    int hits = 0;
#if SAMPLES > 1 && defined(PER_SAMPLE)
    for (int s = 0; s < SAMPLES; s++) {
        Frag f = fetch(c, s);
#else
    {
        Frag f = fetch(c, 0);
#if SAMPLES > 1
        // per-pixel shading: nearest depth, averaged normal and albedo (§6, item 2)
        for (int s = 1; s < SAMPLES; s++) {
            Frag g = fetch(c, s);
            if (g.depth < 1.0) {
                if (f.depth >= 1.0 || g.depth < f.depth) f.depth = g.depth;
                f.n += g.n; f.albedo += g.albedo; f.glow = max(f.glow, g.glow);
            }
        }
        f.albedo = f.albedo.a > 0.0 ? vec4(f.albedo.rgb / f.albedo.a, f.albedo.a / float(SAMPLES))
                                    : vec4(0.0);
#endif
#endif
#if defined(FILL_HOLES) && !defined(LAYER)
        // T-junction holes: a lone background sample amid geometry takes a neighbour's data
        if (f.depth >= 1.0) {
            int n = 0; Frag best = f;
            ivec2 o[4] = ivec2[4](ivec2(1, 0), ivec2(-1, 0), ivec2(0, 1), ivec2(0, -1));
            for (int k = 0; k < 4; k++) {
                Frag g = fetch(clamp(c + o[k], ivec2(0), textureSize(g_depth MS_ARG) - 1), 0);
                if (g.depth < 1.0) { n++; if (best.depth >= 1.0) best = g; }
            }
            if (n >= 3) f = best;
        }
#endif
        if (f.depth < 1.0) {
            float dist;
            acc += shade(f, v_uv, dist);
            dmin = min(dmin, dist);
            nsum += f.n;
            hits++;
        }
    }
#if SAMPLES > 1 && defined(PER_SAMPLE)
    acc /= float(SAMPLES);
#endif
    out_color = acc;
#ifndef LAYER
    // coverage in alpha: the composite blends the sky behind partly covered edge pixels
    out_front = vec4(hits > 0 ? dmin : 1e9, hits > 0 ? normalize(nsum) : vec3(0.0));
#endif
}
