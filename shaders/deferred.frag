// Deferred light for one layer (opaque or a depth-peeling layer), thesis §5.4:
// world position from depth, then include/shade.glsl (light volume + eq. 4.1, sun/moon
// shadow map, fog); the opaque layer also closes the shown area's outer wall
// (include/walls.glsl).
// Defines: SAMPLES, PER_SAMPLE, SHADOWS, LAYER (peel layer: premultiplied alpha
// out), COVERED (drawn against the coverage of its G-buffer, cover.frag, or without
// MSAA against a peel layer's own depth, read from its copy, ZCOPY: only pixels
// with a surface run; the opaque layer's other pixels are SKY's), SKY (the opaque
// layer's other pixels, from a camera inside the area: those with no surface (the
// holes' fill, the outer wall) and those in the fade band, with the sky or the sea
// behind them, which the composite then leaves: its SKY_DONE), FOG, FILL_HOLES
// (T-junction holes), DEBUG (1 albedo, 2 normal, 3 depth, 4 light, 5 aggregation).
#include "include/common.glsl"
#include "include/shade.glsl"
#ifndef LAYER
#include "include/walls.glsl"
#endif

//@ sampler gdepth2D g_depth    if !defined(ZCOPY)
//@ sampler sampler2D g_depth  if ZCOPY  // a one-sample peel layer's copy (its depth is bound)
//@ sampler gsampler2D g_albedo
//@ sampler gsampler2D g_normal
//@ out 0 vec4 out_color
//@ out 1 vec4 out_front  if !defined(LAYER)  // distance, normal: for SSAO, DOF, god rays

struct Frag { float depth; vec4 albedo; vec3 n; float glow; };

Frag fetch(ivec2 c, int s) {
    Frag f;
    f.depth = FETCH(g_depth, c, s).r;
    f.albedo = FETCH(g_albedo, c, s);
    vec4 nn = FETCH(g_normal, c, s);
    f.n = nn.xyz * 2.0 - 1.0;
    f.glow = nn.a;
    return f;
}

void main() {
    ivec2 c = ivec2(gl_FragCoord.xy);
#if defined(LAYER) && !defined(COVERED)
    // most of a peel layer is empty (the second and third: all of it, mostly): those
    // pixels read only their depths and leave. On a GPU, this heavy shader runs few
    // threads at once, so each texture read it waits for is slow (an empty layer's
    // pass cost 4.6x the old one's on an H200 before this).
    bool covered = false;
    for (int s = 0; s < SAMPLES; s++) covered = covered || FETCH(g_depth, c, s).r < 1.0;
    if (!covered) { out_color = vec4(0.0); return; }
#endif
    vec2 px = 1.0 / vec2(textureSize(g_depth MS_ARG));
    vec4 acc = vec4(0.0);
    float dmin = 1e9;
    vec3 nsum = vec3(0.0);
    int hits = 0;
#if !defined(LAYER) && !defined(COVERED)
    // the shown area's outer wall where the meshes have none (include/walls.glsl): the
    // ray's one wall point, once per pixel, in place of what is behind it. From inside
    // the area a ray only meets it where nothing is drawn (it left through the ground or
    // a cave), so only those pixels look for it there.
    vec3 wp = vec3(0.0), wn = vec3(0.0);
    int row = 0;
#ifdef SKY
    bool outside = false;  // (SKY: a camera inside the area)
#else
    bool outside = ortho || any(lessThan(cam_pos.xy, area_box.xy))
                         || any(greaterThanEqual(cam_pos.xy, area_box.zw));
#endif
    bool wall = walls && (outside || FETCH(g_depth, c, 0).r >= 1.0)
                && wall_hit(v_uv, wp, wn, row);
    float wall_d = wall ? eye_dist(wp) : 1e9;
    vec4 wall_c = wall ? wall_albedo(wp, row, v_uv, px.y) : vec4(0.0);
#endif
#if SAMPLES > 1 && defined(PER_SAMPLE)
    // a pixel inside one surface (every sample covered, with the same albedo, normal
    // and glow: one primitive's fragment, or identical neighbours) is shaded once, at
    // its samples' mean depth (the pixel centre's on a plane); only pixels on edges
    // are shaded per sample. Most of a frame's pixels: up to SAMPLES x less work.
    Frag f0 = fetch(c, 0);
    bool same = f0.depth < 1.0;
    float dsum = f0.depth;
    for (int s = 1; s < SAMPLES && same; s++) {
        Frag g = fetch(c, s);
        same = g.depth < 1.0 && g.albedo == f0.albedo && g.n == f0.n && g.glow == f0.glow;
        dsum += g.depth;
    }
    if (same) f0.depth = dsum / float(SAMPLES);
    int shaded = same ? 1 : SAMPLES;
    for (int s = 0; s < shaded; s++) {
        Frag f = s == 0 ? f0 : fetch(c, s);
#else
    {
        Frag f = fetch(c, 0);
#if SAMPLES > 1
        // per-pixel shading: nearest depth, averaged normal and albedo (§6, item 2)
        for (int s = 1; s < SAMPLES; s++) {
            Frag g = fetch(c, s);
            if (g.depth < 1.0) {
                if (f.depth >= 1.0 || g.depth < f.depth) f.depth = g.depth;
                f.n += g.n; f.albedo += g.albedo; f.glow = max(f.glow, g.glow);
            }
        }
        f.albedo = f.albedo.a > 0.0 ? vec4(f.albedo.rgb / f.albedo.a, f.albedo.a / float(SAMPLES))
                                    : vec4(0.0);
#endif
#endif
#if defined(FILL_HOLES) && !defined(LAYER) && !defined(COVERED)
        // T-junction holes: a lone background sample amid geometry takes a neighbour's data
        if (f.depth >= 1.0) {
            int n = 0; Frag best = f;
            ivec2 o[4] = ivec2[4](ivec2(1, 0), ivec2(-1, 0), ivec2(0, 1), ivec2(0, -1));
            for (int k = 0; k < 4; k++) {
                Frag g = fetch(clamp(c + o[k], ivec2(0), textureSize(g_depth MS_ARG) - 1), 0);
                if (g.depth < 1.0) { n++; if (best.depth >= 1.0) best = g; }
            }
            if (n >= 3) f = best;
        }
#endif
        vec3 p = scene_pos(v_uv, f.depth);
        vec4 albedo = f.albedo;
        vec3 n = f.n;
        float glow = f.glow;
#if !defined(LAYER) && !defined(COVERED)
        if (wall && (f.depth >= 1.0 || wall_d < eye_dist(p) - 1e-3)) {
            p = wp; albedo = wall_c; n = wn; glow = 0.0;
            f.depth = 0.0;  // (drawn)
        }
#endif
        if (f.depth < 1.0) {
            // (a chunk's surface, or far terrain's: include/lightvol.glsl's spare)
            float spare = far_split > 0.0 && f.depth >= far_split ? 0.0 : 1.0;
            acc += shade_surface(albedo, p, normalize(n), glow, spare);
            dmin = min(dmin, eye_dist(p));
            nsum += n;
            hits++;
        }
    }
#if SAMPLES > 1 && defined(PER_SAMPLE)
    acc /= float(shaded);
#endif
#ifdef SKY
    {   // what is behind: the sea, else the sky (composite.frag's, SKY_DONE)
        vec3 dir = ray_dir(v_uv);
        float t = sea_hit(cam_pos, dir);
        vec3 bg = t > 0.0 ? sea_color(cam_pos, cam_pos + dir * t) : background_here(cam_pos, dir);
        acc = vec4(acc.rgb + bg * (1.0 - acc.a), 1.0);
    }
#endif
    out_color = acc;
#ifndef LAYER
    // coverage in alpha: the composite blends the sky behind partly covered edge pixels
    out_front = vec4(hits > 0 ? dmin : 1e9, hits > 0 ? normalize(nsum) : vec3(0.0));
#endif
}
