// Procedural sky, thesis eq. 5.1: base + horizon + halo + disc (sun by day, moon by night).
#include "include/frame.glsl"

// Sky without the disc: the atmosphere colour fog blends toward (§5.4.3).
vec3 sky_base(vec3 n) {
    float k1 = clamp((n.z + 0.1) * 5.0, 0.0, 1.0);
    k1 *= k1;
    float d = length(sky_light_dir - n);
    return sky_zenith * (0.4 + 0.6 * k1)
         + sky_horizon * (1.0 - abs(n.z))
         + sky_halo * max(0.0, 1.0 - d * 0.5);
}

// The disc is measured in pixels (screen space) so it stays round (fig. 5.24).
vec3 sky_color(vec3 n, float d_px, float size_px) {
    vec3 c = sky_base(n);
    float k = pow(min(1.0, size_px / max(d_px, 1e-3)), 8.0);
    if (dot(n, sky_light_dir) > 0.0) c += sky_disc * k;
    if (sky_stars > 0.0 && n.z > 0.0) {
        vec3 q = floor(n * 300.0);
        float h = fract(sin(dot(q, vec3(12.9898, 78.233, 37.719))) * 43758.5453);
        c += vec3(step(0.9985, h) * sky_stars * 0.8 * n.z);
    }
    return c;
}
