// Water and glass surfaces: the waving normal of the water's top, Fresnel (Schlick),
// the sky (and clouds) in the reflection, the sun's glint; and the sea plane that
// continues the water to the horizon beyond the shown area (sea_z, area_box).
#ifndef WATER_GLSL
#define WATER_GLSL
#include "include/clouds.glsl"

// deep water's colour: block.frag's water_body of the water texture, deep (linear)
#define WATER_DEEP vec3(0.0018, 0.029, 0.08)

// Slopes of a few directional waves (world xy, seconds), fading out with distance so
// far water does not sparkle.
vec2 wave_slope(vec2 xy, float dist) {
    float k = 1.0 - smoothstep(30.0, 160.0, dist);
    if (k <= 0.0) return vec2(0.0);
    vec2 s = vec2(0.0);
    float t = waving ? time : 0.0;  // still water when the view stands still
    const vec4 w[4] = vec4[4](vec4(0.8, 0.6, 0.9, 1.3), vec4(-0.5, 0.85, 1.7, 1.9),
                              vec4(0.95, -0.3, 2.9, 2.7), vec4(-0.2, -0.98, 4.3, 3.4));
    for (int i = 0; i < 4; i++) {
        float ph = dot(w[i].xy, xy) * w[i].z + t * w[i].w;
        s += w[i].xy * cos(ph) * (0.05 / (1.0 + float(i) * 0.6));
    }
    s += 0.04 * vec2(gnoise2(xy * 0.9 + t * 0.3, 7u), gnoise2(xy.yx * 0.9 - t * 0.25, 11u));
    return s * k;
}

vec3 water_normal(vec3 p, vec3 n, float dist) {
    if (n.z < 0.5) return n;
    return normalize(vec3(-wave_slope(p.xy, dist), 1.0));
}

float fresnel(float f0, float cos_v) {
    float m = 1.0 - clamp(cos_v, 0.0, 1.0);
    return f0 + (1.0 - f0) * m * m * m * m * m;
}

// What a surface at p with normal n reflects towards the eye looking along v (unit,
// eye to p): the sky and clouds (with_clouds), and the sun's glint (times `direct`:
// shadowed, 0..1). Far away the waves smaller than a pixel blur the clouds away.
vec3 reflection(vec3 p, vec3 v, vec3 n, float direct, bool with_clouds) {
    vec3 r = reflect(v, n);
    r.z = max(r.z, 0.0);  // waves that reflect downwards still see the horizon
    r = normalize(r + vec3(0.0, 0.0, 1e-3));
    float near = with_clouds ? 1.0 - smoothstep(60.0, 400.0, distance(p, cam_pos)) : 0.0;
    vec4 cl = near > 0.0 ? cloud_layer(p, r) * near : vec4(0.0);
    vec3 c = sky_radiance(r) * (1.0 - cl.a) + cl.rgb;
    // a sharp highlight of the disc (the sun's or moon's), dimmed where clouds cover it
    float k = max(dot(r, sky_light_dir), 0.0);
    float g = pow(k, 900.0) * 40.0 + pow(k, 120.0) * 1.2;
    return c + sky_disc * 0.06 * g * direct * (1.0 - cl.a) * step(0.0, sky_light_dir.z);
}

// Distance along d from ro to the sea's top, or -1 where the ray does not meet it.
float sea_hit(vec3 ro, vec3 d) {
    if (!sea || d.z >= -1e-5 || ro.z <= sea_z) return -1.0;
    return (sea_z - ro.z) / d.z;
}

bool in_area(vec2 xy) { return all(greaterThanEqual(xy, area_box.xy)) && all(lessThan(xy, area_box.zw)); }

// The open sea at p (on the plane), seen from ro: deep water lit like the terrain, the
// reflection of the sky over it by Fresnel (not of the clouds: it lies beyond the shown
// area, where they would be blurred away, and they cost most), the haze of the way.
vec3 sea_color(vec3 ro, vec3 p) {
    vec3 v = normalize(p - ro);
    float dist = distance(ro, p);
    vec3 n = water_fx ? water_normal(p, vec3(0.0, 0.0, 1.0), dist) : vec3(0.0, 0.0, 1.0);
    vec3 body = WATER_DEEP * (day_ambient + day_direct * max(sky_light_dir.z, 0.0));
    // far away many waves per pixel: the grazing mirror averages to less
    float f = water_fx ? fresnel(0.02, max(dot(-v, n), 0.12)) : 0.0;
    // (the clouds' shadow only matters for the glint, near the disc's reflection)
    bool glint = water_fx && dot(reflect(v, n), sky_light_dir) > 0.99;
    vec3 c = mix(body, reflection(p, v, n, glint ? cloud_shadow(p) : float(water_fx), false), f);
    return mix(c, haze_color(v), haze(ro, p));
}
#endif
