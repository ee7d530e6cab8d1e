// Per-surface shading, the one place for it: the deferred pass (deferred.frag, from a
// G-buffer) and the forward OIT pass (block.frag with OIT) both call shade_surface.
// Light volume + eq. 4.1 (include/lightvol.glsl -> light.glsl), sun/moon shadow map
// with PCF (§5.4.1), distance fog (§5.4.3), the debug views.
// Defines: SHADOWS, FOG, DEBUG (1 albedo, 2 normal, 3 depth, 4 light, 5 aggregation).
#include "include/lightvol.glsl"
#include "include/eye.glsl"
#include "include/sky.glsl"

#ifndef DEBUG
#define DEBUG 0
#endif

//@ sampler depth2D shadow_map  if SHADOWS

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
    // 2x2 PCF in one gather, bilinearly weighted (§5.4.1): the four depths (a gather
    // neither filters nor needs a compare mode, only the clamp every device binds),
    // compared here as a shadow sampler's gather would
    vec2 size = vec2(textureSize(shadow_map, 0));
    vec2 t = s.xy * size - 0.5;
    vec2 f = fract(t);
    vec4 g = vec4(lessThanEqual(vec4(ref), textureGather(shadow_map, (floor(t) + 1.0) / size)));
    float lit = mix(mix(g.w, g.z, f.x), mix(g.x, g.y, f.x), f.y);
    return mix(lit, 1.0, clamp(dist / shadow_fade, 0.0, 1.0));
#else
    return 1.0;
#endif
}

// Eq. 4.1 (light.glsl) with the direct term dimmed by the shadow map.
vec3 shade_light(vec3 albedo, vec3 p, vec3 n, float glow) {
    vec4 l = light_volume(p, n);
    DayLight dl = DayLight(day_ambient, day_direct * shadow_at(p, n), sky_light_dir, day_u);
    return light_shade(albedo, l.rgb, glow, l.a, n, dl);
}

// Premultiplied colour of world point p on a surface with unit normal n; albedo.a is
// its opacity (or MSAA coverage).
vec4 shade_surface(vec4 albedo, vec3 p, vec3 n, float glow) {
#if DEBUG == 1 || DEBUG == 5
    return vec4(albedo.rgb, 1.0) * albedo.a;
#elif DEBUG == 2
    return vec4(n * 0.5 + 0.5, 1.0) * albedo.a;
#elif DEBUG == 3
    float dist = eye_dist(p);
    return vec4(vec3(1.0 - pow(clamp(dist / far_dist, 0.0, 1.0), 0.5)), 1.0) * albedo.a;
#else
#if DEBUG == 4
    vec3 c = shade_light(vec3(1.0), p, n, glow);
#else
    vec3 c = shade_light(albedo.rgb, p, n, glow);
#endif
#ifdef FOG
    // horizontal distance: the area ends sideways, a high camera looking down sees clearly
    float k = clamp((length(p.xy - cam_pos.xy) - fog_start) / max(fog_end - fog_start, 1e-3),
                    0.0, 1.0);
    c = mix(c, sky_base(eye_dir(p)), k * k);
#endif
    return vec4(c * albedo.a, albedo.a);
#endif
}
