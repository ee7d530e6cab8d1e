// The physical sky (voxel_addon/light/atmosphere.py: single scattering with ozone, the
// model of Blender's Sky Texture), stars and the haze that thins with altitude.
// render/sky.py tabulates the sky's radiance per hour over SKY_NE elevations (spaced
// by sqrt(sin e), dense at the horizon) x SKY_NA azimuths from the sun's (0..pi, the
// sky is symmetric about the sun's vertical) in the frame block: sky_a holds all but
// the sun's Mie scattering, sky_b that without its phase, which is applied here per
// pixel (its peak around the sun is too sharp for any table). Both hold the log of
// the radiance (plus SKY_EPS), interpolated in log: the sky falls off exponentially
// into the earth's shadow at dusk, and linear steps would show as seams. Values are
// the scene's linear light, already times the hour's exposure (light/daytime.py).
#ifndef ATMOSPHERE_GLSL
#define ATMOSPHERE_GLSL
#include "include/frame.glsl"
#include "include/noise.glsl"

#define SKY_NE 9
#define SKY_NA 9
#define SKY_EPS 1e-6
#define SKY_MIE_G 0.8

float phase_mie(float c) {
    const float g = SKY_MIE_G, g2 = SKY_MIE_G * SKY_MIE_G;
    return 0.119366 * (1.0 - g2) * (1.0 + c * c)
         / ((2.0 + g2) * pow(max(1.0 + g2 - 2.0 * g * c, 1e-4), 1.5));
}

// Sky radiance towards unit direction d at or above the horizon (d.z is clamped to 0).
vec3 sky_radiance(vec3 d) {
    float e = sqrt(clamp(d.z, 0.0, 1.0)) * float(SKY_NE - 1);
    vec2 h = d.xy, s = sun_dir.xy;
    float lh = length(h), ls = length(s);
    float ca = (lh > 1e-5 && ls > 1e-5) ? dot(h, s) / (lh * ls) : 1.0;
    float a = acos(clamp(ca, -1.0, 1.0)) * (float(SKY_NA - 1) / 3.14159265);
    int i = min(int(e), SKY_NE - 2), j = min(int(a), SKY_NA - 2);
    float fi = e - float(i), fj = a - float(j);
    int k = i * SKY_NA + j;
    vec3 A = mix(mix(sky_a[k].rgb, sky_a[k + 1].rgb, fj),
                 mix(sky_a[k + SKY_NA].rgb, sky_a[k + SKY_NA + 1].rgb, fj), fi);
    vec3 B = mix(mix(sky_b[k].rgb, sky_b[k + 1].rgb, fj),
                 mix(sky_b[k + SKY_NA].rgb, sky_b[k + SKY_NA + 1].rgb, fj), fi);
    return max(exp(A) - SKY_EPS, 0.0) + phase_mie(dot(d, sun_dir)) * max(exp(B) - SKY_EPS, 0.0);
}

// The haze's colour looking along d: the air near the ground lit by the light there
// (eq. 4.1's daylight, brighter looking towards the sun or moon) where the horizon's
// sky in that azimuth (the light of all the air out to the end of the atmosphere) is
// brighter than that, else the horizon's sky. (After sunset the far air is still in
// the sun and the horizon glows; the air around the eye is not, and neither is its
// haze.)
// The horizon row of the sky table (sky_radiance at elevation 0) at azimuth index a
// from the sun, the Mie part by cosine c to the sun.
vec3 horizon_sky(float a, float c) {
    int j = min(int(a), SKY_NA - 2);
    float fj = a - float(j);
    return max(exp(mix(sky_a[j].rgb, sky_a[j + 1].rgb, fj)) - SKY_EPS, 0.0)
         + phase_mie(c) * max(exp(mix(sky_b[j].rgb, sky_b[j + 1].rgb, fj)) - SKY_EPS, 0.0);
}

vec3 haze_color(vec3 d) {
    vec2 h = d.xy / max(length(d.xy), 1e-5);
    vec2 s = sun_dir.xy / max(length(sun_dir.xy), 1e-5);
    float a = acos(clamp(dot(h, s), -1.0, 1.0)) * (float(SKY_NA - 1) / 3.14159265);
    // Looking down, the way through the air is short and the horizon's glow towards the
    // sun is not in it: the haze turns to the local air's light. Without it the glow ran
    // straight down the screen below the sunset (a hard-edged red band over the ground
    // and the background below the horizon).
    float down = smoothstep(-0.05, 0.7, -d.z);
    vec3 local = day_ambient + day_direct * (0.2 + 0.8 * pow(max(dot(h, sky_light_dir.xy), 0.0), 8.0));
    vec3 sky = mix(horizon_sky(a, dot(vec3(h, 0.0), sun_dir)), local, down);
    const vec3 Y = vec3(0.2126, 0.7152, 0.0722);
    float q = dot(sky, Y) / max(dot(local, Y), 1e-6);
    float k = inversesqrt(1.0 + q * q);  // ~1 where the sky is the dimmer, ~1/q where not
    // capped, and in the local light's colour the more the sky outshines it (the
    // horizon's glow at dusk is far too saturated for the air in front of the ground)
    return mix(local, sky * k, k);
}

// Below the horizon, where neither terrain nor sea is: the horizon darkening downwards
// (the ground's colour under the haze), so a view from above does not look into a hole.
vec3 sky_below(vec3 d) {
    return haze_color(d) * mix(1.0, 0.45, smoothstep(0.0, 0.35, -d.z));
}

// Haze between the eye at e and the point p: density fog_density at sea level (sea_z)
// and below, falling by 1/e every fog_height blocks up. Returns the fraction of p's
// light lost.
float haze(vec3 e, vec3 p) {
    if (fog_density <= 0.0) return 0.0;
    float len = distance(e, p);
    e.z = max(e.z, sea_z);
    p.z = max(p.z, sea_z);
    float dz = (p.z - e.z) / fog_height;
    float base = exp(-(e.z - sea_z) / fog_height);
    // the integral of exp(-z) along the segment, stable when it is level
    float k = abs(dz) > 1e-3 ? (1.0 - exp(-dz)) / dz : 1.0 - 0.5 * dz;
    return 1.0 - exp(-fog_density * len * base * k);
}

// Stars: one candidate per cell of a cube map on the celestial sphere (it turns with
// the sun around sky_pole), a round point a pixel wide at a random place in its cell;
// few are bright. vx_mix is the generators' hash (include/noise.glsl).
vec3 stars(vec3 d) {
    if (!starry || d.z <= 0.0) return vec3(0.0);
    vec3 u = normalize(cross(sky_pole, sun_dir));
    vec3 v = cross(sky_pole, u);
    vec3 q = vec3(dot(d, u), dot(d, v), dot(d, sky_pole));
    vec3 a = abs(q);
    vec2 uv;
    uint face;
    if (a.x >= a.y && a.x >= a.z) { uv = q.yz / a.x; face = q.x > 0.0 ? 0u : 1u; }
    else if (a.y >= a.z) { uv = q.xz / a.y; face = q.y > 0.0 ? 2u : 3u; }
    else { uv = q.xy / a.z; face = q.z > 0.0 ? 4u : 5u; }
    const float cells = 110.0;  // per face side: cells of ~0.5-0.8 degrees
    vec2 g = (uv * 0.5 + 0.5) * cells;
    vec2 c = floor(g);
    uint h = vx_mix(uint(c.x) * 0x8da6b343u + uint(c.y) * 0xd8163841u + face * 0xcb1ab31fu + 77u);
    float keep = float(h >> 22) / 1023.0;
    if (keep < 0.96) return vec3(0.0);
    vec2 at = c + 0.3 + 0.4 * vec2(float(h & 255u), float((h >> 8) & 255u)) / 255.0;
    float px = (2.0 / cells) / (1.0 + dot(uv, uv)) / max(star_px, 1e-5);  // pixels per cell
    float r = length(g - at) * px;
    vec2 f = g - c;
    float edge = min(min(f.x, 1.0 - f.x), min(f.y, 1.0 - f.y)) * px;  // pixels to the cell's edge
    float b = (keep - 0.96) / 0.04;
    vec3 tint = mix(vec3(0.7, 0.82, 1.0), vec3(1.0, 0.86, 0.7), float((h >> 16) & 7u) / 7.0);
    // fainter in the haze near the horizon
    return tint * (0.08 + 2.5 * b * b * b * b) * exp(-r * r * 2.0) * smoothstep(0.0, 1.0, edge)
         * sky_stars * smoothstep(0.0, 0.3, d.z);
}
#endif
