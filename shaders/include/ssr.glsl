// Screen-space reflection (issue 20): water reflects the opaque scene where the
// reflected ray meets it on screen (the deferred pass's outputs: its colour, and the
// `front` distance to compare with), else the sky (include/water.glsl reflection). The
// ray is marched in world space with growing steps, each step projected and compared
// with the drawn distance there; a hit is refined by bisection. Peel layers only
// (LAYER): they are shaded after the opaque scene. Frame member: ssr.
#ifndef SSR_GLSL
#define SSR_GLSL
#include "include/eye.glsl"

//@ sampler sampler2D ssr_color  if defined(LAYER)  // the opaque scene, premultiplied
//@ sampler sampler2D ssr_front  if defined(LAYER)  // its distance (r; 1e9: none)

#define SSR_STEPS 16  // 0.5 .. ~220 blocks

// where world point q lands on screen (uv) and whether it does
bool ssr_uv(vec3 q, out vec2 uv) {
    vec4 c = vp * vec4(q, 1.0);
    uv = c.xy / max(c.w, 1e-6) * 0.5 + 0.5;
    return c.w > 1e-4 && all(greaterThanEqual(uv, vec2(0.0))) && all(lessThan(uv, vec2(1.0)));
}

// how far behind the drawn surface at q's pixel q lies (negative: in front of it)
float ssr_behind(vec3 q, vec2 uv, vec2 size) {
    return eye_dist(q) - texelFetch(ssr_front, ivec2(uv * size), 0).r;
}

// (colour, weight) of what the ray from p along unit r meets on screen; weight 0 where
// it leaves the screen first or meets nothing. Every way it ends fades: towards the
// screen's edges, towards the march's reach, and where the ray passes far behind the
// surface (it went behind something: it marches on for what is beyond, as a ray past a
// tree meets the hill behind it). Cut off at once, each showed as a hard edge between
// the scene's and the sky's reflection.
vec4 ssr_trace(vec3 p, vec3 r) {
    vec2 size = vec2(textureSize(ssr_front, 0));
    float t0 = 0.0, t = 0.5;
    vec2 uv;
    for (int i = 0; i < SSR_STEPS; i++) {
        vec3 q = p + r * t;
        if (q.z > 256.0 || !ssr_uv(q, uv)) return vec4(0.0);  // (nothing above the world)
        float b = ssr_behind(q, uv, size);
        float thick = (t - t0) * 1.5 + 0.5;
        if (b > 0.0 && b < 2.0 * thick) {
            for (int k = 0; k < 5; k++) {  // the surface between t0 and t
                float tm = 0.5 * (t0 + t);
                vec2 um;
                if (!ssr_uv(p + r * tm, um)) break;
                if (ssr_behind(p + r * tm, um, size) > 0.0) { t = tm; uv = um; } else t0 = tm;
            }
            vec4 c = texelFetch(ssr_color, ivec2(uv * size), 0);
            vec2 e = abs(uv - 0.5) * 2.0;  // fade towards the screen's edges
            float w = (1.0 - smoothstep(0.7, 1.0, max(e.x, e.y))) * c.a
                    * (1.0 - smoothstep(110.0, 215.0, t))  // (far hits: coarse steps)
                    * (1.0 - smoothstep(thick, 2.0 * thick, b));  // (behind, not into it)
            return vec4(c.rgb / max(c.a, 1e-3), w);
        }
        t0 = t;
        t *= 1.5;
    }
    return vec4(0.0);
}
#endif
