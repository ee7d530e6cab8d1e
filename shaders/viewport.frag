// The pipeline's frame into Blender's viewport (blender/liveview/composite.py): colour of the
// final pass, depth converted to Blender's projection so the depth test (LEQUAL,
// set by the caller) mixes voxels and Blender's objects both ways. Where the
// pipeline drew no surface the sky goes at the far plane (only where Blender drew
// nothing), or nothing at all when the sky is off.
// Defines: SAMPLES (G-buffer), LAYERS (1: the nearest transparent layer hides too),
// FOLD (the frame is the region's size: the final pass folded in, include/final.glsl, from its inputs
// `sharp` and with DOF `blurred`, instead of its output `color`: one full-region pass
// and the RGBA8 image's write and read fewer), DOF (as final.frag's),
// KEEP (into the region's kept targets instead: colour with alpha 0 where nothing
// goes, and the depth as a value; viewport_kept.frag draws them, again while still).
#include "include/common.glsl"
#include "include/frame.glsl"
#include "include/eye.glsl"
#if FOLD
#include "include/final.glsl"
#endif

//@ sampler sampler2D color        if !FOLD  // final pass, display values
//@ sampler sampler2D sharp        if FOLD   // the final pass's inputs (final.frag)
//@ sampler sampler2D blurred      if FOLD && DOF
//@ sampler gdepth2D g_depth
//@ sampler gdepth2D prev_depth   if LAYERS > 0  // first depth-peeling layer
//@ push mat4 host_vp             // Blender's perspective_matrix (window @ view)
//@ push bool sky
//@ push int srgbTarget           // set by Blender (common.glsl, to_target)
//@ out 0 vec4 out_color
//@ out 1 float out_depth         if KEEP
//@ depth_write                   if !KEEP

float nearest(ivec2 c) {
    float d = 1.0;
    for (int s = 0; s < SAMPLES; s++) {
        d = min(d, FETCH(g_depth, c, s).r);
#if LAYERS > 0
        d = min(d, FETCH(prev_depth, c, s).r);
#endif
    }
    return d;
}

void main() {
    ivec2 size = textureSize(g_depth MS_ARG);
    ivec2 px = clamp(ivec2(v_uv * vec2(size)), ivec2(0), size - 1);
    float d = nearest(px);
    float z;
    if (d >= 1.0) {
        if (!sky) {
#if KEEP
            out_color = vec4(0.0);
            out_depth = 1.0;
            return;
#else
            discard;
#endif
        }
        z = 1.0;
    } else {
        // Blender keeps GL's conventions on every backend: NDC depth -1..1 -> 0..1
        vec4 c = host_vp * vec4(scene_pos(v_uv, d), 1.0);
        z = clamp(c.z / c.w, -1.0, 1.0) * 0.5 + 0.5;
    }
    // into Blender's sRGB framebuffer or the kept frame's sRGB texture: both encode
    // what is written; a draft frame is smaller: its final colour filtered
#if FOLD
    vec3 rgb = final_color(v_uv);
#else
    vec3 rgb = bilinear(color, v_uv).rgb;
#endif
    out_color = vec4(to_target(rgb, srgbTarget), 1.0);
#if KEEP
    out_depth = z;
#else
    gl_FragDepth = z;
#endif
}
