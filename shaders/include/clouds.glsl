// A cloud layer: a plane at height cloud_z whose cover is fBm of the generators' noise
// (include/noise.glsl), drifting with the time of day (cloud_drift, render/sky.py) in
// two layers at different speeds so the shapes change as they go; lit by the sun or
// moon with a self-shadow towards it, and casting soft shadows on the terrain. The
// NumPy twin of cloud_density is voxel_addon/render/clouds.py.
#ifndef CLOUDS_GLSL
#define CLOUDS_GLSL
#include "include/noise.glsl"
#include "include/atmosphere.glsl"

#define CLOUD_SCALE 420.0   // blocks per unit of the first octave
#define CLOUD_SEED 0x2545F491u

// Cover at xy in 0..1 with n octaves (fewer far away: no sparkle, less work); a
// second, finer layer of n - 3 octaves (at least 1) drifts slower, so shapes change.
// fbm2 of the first layer, unrolled to stop as soon as the octaves still to come
// (each |gnoise2| <= sqrt(2)/2) cannot bring the sum across the smoothstep: the same
// value, without most of the noise in clear or solid sky.
float cloud_density(vec2 xy, int n) {
    vec2 p = (xy + cloud_drift) / CLOUD_SCALE;
    vec2 q = (xy + cloud_drift * 0.6 + vec2(-cloud_drift.y, cloud_drift.x) * 0.25) / (CLOUD_SCALE * 0.45);
    float t = mix(0.35, -0.4, cloud_cover);
    float f = 0.3 * fbm2(q, CLOUD_SEED + 16u, max(n - 3, 1));
    float a = 0.5;
    const mat2 rot = mat2(0.8, 0.6, -0.6, 0.8);
    for (int o = 0; o < 8; o++) {
        if (o >= n) break;
        f += a * gnoise2(p, CLOUD_SEED + uint(o));
        float rest = 0.7072 * a;  // a/2 + a/4 + ... < a
        if (f + rest < t) return 0.0;
        if (f - rest > t + 0.25) return 1.0;
        p = rot * p * 2.0;
        a *= 0.5;
    }
    return smoothstep(t, t + 0.25, f);
}

// The layer seen from ro along d: premultiplied colour and coverage.
vec4 cloud_layer(vec3 ro, vec3 d) {
    if (!clouds || d.z <= 0.0 || ro.z >= cloud_z) return vec4(0.0);
    float t = (cloud_z - ro.z) / d.z;
    if (t > 40000.0) return vec4(0.0);
    vec2 xy = ro.xy + d.xy * t;
    int n = t < 1500.0 ? 4 : (t < 5000.0 ? 3 : 2);
    float a = cloud_density(xy, n);
    if (a <= 0.001) return vec4(0.0);
    vec3 l = sky_light_dir;
    // light that reaches this point through the cloud above it, towards the light (far
    // away a pixel covers too much cloud to tell)
    float towards = t < 5000.0 ? cloud_density(xy + l.xy / max(l.z, 0.2) * 60.0, 2) : 0.3;
    float lit = exp(-2.2 * towards) * (0.55 + 0.45 * (1.0 - a));
    float fwd = 1.0 + 1.5 * pow(max(dot(d, l), 0.0), 6.0);  // silver lining towards the sun
    vec3 c = cloud_sun * lit * fwd + cloud_sky * (1.0 - 0.35 * a);
    // far clouds sink into the horizon's haze
    float far = exp(-t / 14000.0);
    c = mix(haze_color(d), c, far);
    a *= smoothstep(0.0, 0.06, d.z) * mix(0.4, 0.95, far);
    return vec4(c * a, a);
}

// The fraction of direct light that passes the clouds towards the light from p.
float cloud_shadow(vec3 p) {
    vec3 l = sky_light_dir;
    if (!clouds || !cloud_shadows || l.z <= 0.02 || p.z >= cloud_z) return 1.0;
    vec2 xy = p.xy + l.xy * ((cloud_z - p.z) / l.z);
    return 1.0 - 0.7 * cloud_density(xy, 1);  // soft: the coarse shapes only
}
#endif
