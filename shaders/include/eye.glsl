// Rays of the drawn camera, perspective or orthographic (Camera.from_matrices). The
// "front" distance buffer holds eye_dist: from the eye point (perspective) or from
// the eye plane (orthographic, where every ray runs along cam_fwd).
#ifndef EYE_GLSL
#define EYE_GLSL
#include "include/frame.glsl"
#include "include/common.glsl"

// World position of a G-buffer depth. With far terrain (render/far.py) the depth
// range is split: near chunks in [0, far_split) by vp, far tiles from far_split on by
// their own projection (a 4 km range at the near chunks' precision).
vec3 scene_pos(vec2 uv, float depth) {
    return world_pos(far_split > 0.0 && depth >= far_split ? far_inv_vp : inv_vp, uv, depth);
}

float eye_dist(vec3 p) { return ortho ? dot(p - cam_pos, cam_fwd) : length(p - cam_pos); }

// the direction from the eye toward p
vec3 eye_dir(vec3 p) { return ortho ? cam_fwd : normalize(p - cam_pos); }

// the direction of the ray through screen point uv
vec3 ray_dir(vec2 uv) { return ortho ? cam_fwd : normalize(scene_pos(uv, 1.0) - cam_pos); }

// the point at eye_dist d on the ray through uv
vec3 ray_at(vec2 uv, float d) {
    if (!ortho) return cam_pos + ray_dir(uv) * d;
    vec3 o = world_pos(inv_vp, uv, 0.0);  // where the ray crosses the near plane
    return o + cam_fwd * (d - dot(o - cam_pos, cam_fwd));
}
#endif
