// Per-surface shading, the one place for it: the deferred pass (deferred.frag, from a
// G-buffer) and the forward OIT pass (block.frag with OIT) both call shade_surface.
// Light volume + eq. 4.1 (include/lightvol.glsl -> light.glsl), sun/moon shadow map
// with PCF (§5.4.1) and the clouds' shadows, water and glass reflecting the sky
// (include/water.glsl), haze thinning with altitude (§5.4.3, include/atmosphere.glsl),
// the fade into the sky at the edge of the shown area, the debug views.
// Colours are the scene's linear light (albedo arrives sRGB-encoded, as the textures
// are, and is decoded here; final.frag tone-maps). Defines: SHADOWS, FOG, LAYER or OIT
// (blended surfaces), DEBUG (1 albedo, 2 normal, 3 depth, 4 light, 5 aggregation).
#include "include/lightvol.glsl"
#include "include/eye.glsl"
#include "include/sky.glsl"
#include "include/tonemap.glsl"
#ifdef LAYER
#include "include/ssr.glsl"
#endif

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

// Eq. 4.1 (light.glsl) with the direct term dimmed by the shadow map and the clouds.
// The light volume's levels step evenly on screen, as the textures' values do: their
// linear light is level^2.2 (so a scene looks as it did before the tone curve).
// `day` returns the point's linear daylight level (how much sky it sees); `spare`:
// light_volume's (include/lightvol.glsl).
vec3 shade_light_day(vec3 albedo, vec3 p, vec3 n, float glow, float spare, out float day) {
    vec4 l = light_volume(p, n, spare);
    // the shown area's outer wall (closed by Renderer.set_area, or include/walls.glsl)
    // looks out of the lit volume: lit as a cliff open to the sky (its faces' positions
    // come back from the depth buffer within a few hundredths of a block)
    vec2 lo = abs(p.xy - area_box.xy), hi = abs(p.xy - area_box.zw);
    if ((lo.x < 0.02 && n.x < -0.5) || (hi.x < 0.02 && n.x > 0.5) ||
        (lo.y < 0.02 && n.y < -0.5) || (hi.y < 0.02 && n.y > 0.5)) l = vec4(0.0, 0.0, 0.0, 0.85);
    l = pow(l, vec4(2.2));
    day = l.a;
    float direct = l.a > 0.0 && dot(n, sky_light_dir) > 0.0 ? shadow_at(p, n) * cloud_shadow(p) : 1.0;
    DayLight dl = DayLight(day_ambient, day_direct * direct, sky_light_dir, day_u);
    return light_shade(albedo, l.rgb, glow, l.a, n, dl);
}

vec3 shade_light(vec3 albedo, vec3 p, vec3 n, float glow) {
    float day;
    return shade_light_day(albedo, p, n, glow, 0.0, day);
}

// The horizontal distance past which surfaces fade into what is behind them (the sky,
// the sea): the end of the shown area looks like a horizon, not a cut (Settings.fade).
float edge_fade(vec3 p) {
    float k = clamp((length(p.xy - cam_pos.xy) - fade_start) / max(fade_end - fade_start, 1e-3),
                    0.0, 1.0);
    return k * k * (3.0 - 2.0 * k);
}

// Premultiplied colour of world point p on a surface with unit normal n; albedo.a is
// its opacity (or MSAA coverage); spare: light_volume's (1 for the chunks' surfaces,
// 0 for far terrain's).
vec4 shade_surface(vec4 albedo, vec3 p, vec3 n, float glow, float spare) {
#if DEBUG == 1 || DEBUG == 5
    return vec4(albedo.rgb, 1.0) * albedo.a;
#elif DEBUG == 2
    return vec4(n * 0.5 + 0.5, 1.0) * albedo.a;
#elif DEBUG == 3
    float dist = eye_dist(p);
    return vec4(vec3(1.0 - pow(clamp(dist / far_dist, 0.0, 1.0), 0.5)), 1.0) * albedo.a;
#else
    bool water = glow >= 0.999;  // block.frag's mark (other glow stays below it)
    if (water) glow = 0.0;
    float day;
#if DEBUG == 4
    vec3 c = shade_light_day(vec3(1.0), p, n, glow, spare, day);
#else
    vec3 c = shade_light_day(srgb_decode(albedo.rgb), p, n, glow, spare, day);
#endif
    vec4 o = vec4(c * albedo.a, albedo.a);
#if (defined(LAYER) || defined(OIT)) && DEBUG == 0
    if (water_fx) {  // water and glass reflect the sky, where daylight reaches them
        vec3 v = eye_dir(p);
        vec3 m = water ? water_normal(p, n, eye_dist(p)) : n;
        float f = fresnel(water ? 0.02 : 0.04, dot(-v, m));
        float direct = day * (sky_light_dir.z > 0.0 ? shadow_at(p, n) * cloud_shadow(p) : 0.0);
        vec3 r = reflection(p, v, m, direct, true) * day;
#ifdef LAYER
        // the scene where the reflected ray meets it on screen (not where the water
        // reflects too little to show it: steep views)
        if (water && ssr && f > 0.06) {
            vec3 rd = reflect(v, m);
            vec4 s = ssr_trace(p, normalize(vec3(rd.xy, max(rd.z, 1e-3))));
            r = mix(r, s.rgb, s.a);
        }
#endif
        o = vec4(o.rgb * (1.0 - f) + r * f, o.a + f * (1.0 - o.a));
    }
#endif
#if !defined(LAYER) && !defined(OIT) && DEBUG == 0
    // Opaque water (the far tiles': no peeled layer behind them) looks like the open sea
    // (water.glsl's sea_color, haze apart) and the near water: its body (far/mesh.py's
    // colour of the water over its floor, deep water's where deep) and the sky's
    // reflection. Its albedo alone made it a flat blue, another colour than the near
    // water and the sea plane beside it, and dark under a bright dusk sky.
    if (water && far_water) {
        vec3 v = eye_dir(p);
        vec3 m = water_normal(p, n, eye_dist(p));
        float f = fresnel(0.02, max(dot(-v, m), 0.12));
        o = vec4(mix(c, reflection(p, v, m, day, false) * day, f) * albedo.a, albedo.a);
    }
#endif
#ifdef FOG
    // outdoor air: none in caves (the surface's daylight stands for the way's)
    float h = haze(cam_pos, p) * sqrt(day);
    if (h > 1e-3) o.rgb = mix(o.rgb, haze_color(eye_dir(p)) * o.a, h);
#endif
    return o * (1.0 - edge_fade(p));
#endif
}
