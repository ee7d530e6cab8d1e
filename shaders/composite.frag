// First global pass (§5.4): sky behind the opaque layer, peel layers back to front,
// SSAO, god rays sampled across the whole sun disc (fixes fig. 5.23).
// Defines: LAYERS (0..3), SSAO, GODRAYS.
#include "include/eye.glsl"
#include "include/sky.glsl"

//@ sampler sampler2D opaque
//@ sampler sampler2D front
//@ sampler sampler2D layer0  if LAYERS > 0
//@ sampler sampler2D layer1  if LAYERS > 1
//@ sampler sampler2D layer2  if LAYERS > 2
//@ sampler sampler2D ao      if SSAO
//@ out 0 vec4 out_color

float godrays(vec2 p) {
    // Mitchell/Wesley screen-space rays with an emission that is zero outside the
    // disc, so only the disc is sampled: the full chord toward p (both halves), and
    // two chords beside it, so a half-hidden sun still shines both ways.
    vec2 d = sun_px - p;
    float len = length(d);
    vec2 dir = len > 1e-3 ? d / len : vec2(1.0, 0.0);
    vec2 perp = vec2(-dir.y, dir.x);
    vec2 size = vec2(textureSize(front, 0));
    float vis = 0.0;
    const int N = 12;
    for (int i = 0; i < N; i++) {
        float t = (float(i) + 0.5) / float(N) * 2.0 - 1.0;
        float s = (float(i % 3) - 1.0) * 0.5;
        vec2 q = sun_px + (dir * t + perp * s * sqrt(max(0.0, 1.0 - t * t))) * sun_radius;
        if (any(lessThan(q, vec2(0.0))) || any(greaterThanEqual(q, size))) continue;
        vis += texelFetch(front, ivec2(q), 0).r > 1e8 ? 1.0 : 0.0;
    }
    vis /= float(N);
    return vis * exp(-len / (0.35 * size.y));
}

void main() {
    vec2 size = vec2(textureSize(opaque, 0));
    vec3 dir = ray_dir(v_uv);
    vec3 sky = sky_color(dir, sun_visible ? distance(gl_FragCoord.xy, sun_px) : 1e9, sun_radius);
    vec4 o = texture(opaque, v_uv);
#ifdef SSAO
    o.rgb *= texture(ao, v_uv).r;
#endif
    vec3 c = o.rgb + sky * (1.0 - o.a);
    // back to front over premultiplied layers
#if LAYERS > 2
    vec4 l2 = texture(layer2, v_uv); c = c * (1.0 - l2.a) + l2.rgb;
#endif
#if LAYERS > 1
    vec4 l1 = texture(layer1, v_uv); c = c * (1.0 - l1.a) + l1.rgb;
#endif
#if LAYERS > 0
    vec4 l0 = texture(layer0, v_uv); c = c * (1.0 - l0.a) + l0.rgb;
#endif
#ifdef GODRAYS
    if (sun_visible) c += sky_disc * 0.12 * godray_strength * godrays(gl_FragCoord.xy);
#endif
    out_color = vec4(c, texture(front, v_uv).r);
}
