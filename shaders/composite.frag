// First global pass (§5.4): sky (with clouds, or the sea beyond the shown area:
// include/sky.glsl background) behind the opaque layer, peel layers back to front,
// SSAO, god rays sampled across the whole sun disc (fixes fig. 5.23).
// Defines: LAYERS (0..3), SSAO, GODRAYS, SKY_DONE (the opaque layer holds the sky and
// the sea behind already: deferred.frag SKY, a camera inside the area).
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
    vec3 ro = ortho ? world_pos(inv_vp, v_uv, 0.0) : cam_pos;
    vec4 o = texture(opaque, v_uv);
    float front_d = texture(front, v_uv).r;
#ifdef SKY_DONE
    const bool sea_front = false;  // (from inside the area the sea is never in front)
    vec3 sea_c = vec3(0.0), sky = vec3(0.0);
#else
    // the sea: behind what does not cover the pixel, and beyond the shown area in front
    // of what of the area lies below its surface (one evaluation for both)
    float t = sea_hit(ro, dir);
    vec3 hit = ro + dir * t;
    bool sea_front = t > 0.0 && front_d < 1e8 && eye_dist(hit) < front_d && !in_area(hit.xy)
        && distance(hit.xy, cam_pos.xy) >= sea_from;  // (far terrain: from its ring's edge)
    bool sea_behind = t > 0.0 && o.a < 0.999;
    vec3 sea_c = sea_front || sea_behind ? sea_color(ro, hit) : vec3(0.0);
    // parallel rays all look one way: below the horizon (where no sea is) an
    // orthographic view shows the sky as seen that far up, not the ground's haze
    vec3 bg = ortho ? vec3(dir.xy, abs(dir.z)) : dir;
    // (not behind surfaces that cover the pixel: the clouds' noise is the dear part)
    vec3 sky = sea_behind ? sea_c : o.a < 0.999 ? background_here(ro, bg) : vec3(0.0);
#endif
#ifdef SSAO
    o.rgb *= pow(texture(ao, v_uv).r, 2.2);  // a factor on screen, as the light levels
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
    if (sea_front) c = sea_c;
#ifdef GODRAYS
    if (sun_visible) c += sky_disc * godray_strength * godrays(gl_FragCoord.xy);  // (render/sky.py godray_scale)
#endif
    out_color = vec4(c, front_d);
}
