// The sky (thesis §5.5): the physical model of include/atmosphere.glsl instead of eq.
// 5.1's key-framed colours; the disc (sun by day, moon by night) in screen space as eq.
// 5.1's last term (pixels, so it stays round: fig. 5.24); stars; the clouds and the sea
// in front of it (include/clouds.glsl, include/water.glsl).
#ifndef SKY_GLSL
#define SKY_GLSL
#include "include/frame.glsl"
#include "include/water.glsl"

// Sky without the disc: the atmosphere colour fog blends toward (§5.4.3).
vec3 sky_base(vec3 n) { return n.z >= 0.0 ? sky_radiance(n) : sky_below(n); }

// The open sky a little more colourful than the single-scattering model's (it read
// washed out at noon, issue 28): chroma x up to 1.3 from the horizon up (none at the
// horizon, where surfaces fade into the haze's colour of the same model: no seam).
vec3 sky_vivid(vec3 c, vec3 n) {
    float luma = dot(c, vec3(0.2126, 0.7152, 0.0722));
    return max(luma + (1.0 + 0.3 * smoothstep(0.0, 0.35, n.z)) * (c - luma), 0.0);
}

// The disc is measured in pixels (screen space) so it stays round (fig. 5.24).
vec3 sky_color(vec3 n, float d_px, float size_px) {
    vec3 c = sky_vivid(sky_base(n), n);
    float k = pow(min(1.0, size_px / max(d_px, 1e-3)), 8.0);
    if (dot(n, sky_light_dir) > 0.0) c += sky_disc * k * smoothstep(-0.01, 0.02, n.z);
    return c + stars(n);
}

// What lies behind every surface along the ray from ro in direction n, where it does
// not meet the sea (sea_hit, sea_color): the sky with its disc and stars, under the clouds.
vec3 background(vec3 ro, vec3 n, float d_px, float size_px) {
    vec4 cl = cloud_layer(ro, n);
    return sky_color(n, d_px, size_px) * (1.0 - cl.a) + cl.rgb;
}

// background() behind this fragment's pixel (the disc where the frame puts the sun).
vec3 background_here(vec3 ro, vec3 n) {
    return background(ro, n, sun_visible ? distance(gl_FragCoord.xy, sun_px) : 1e9, sun_radius);
}
#endif
