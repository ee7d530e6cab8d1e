// A peel layer's coverage as a one-sample depth buffer (fullscreen.vert): each pixel's
// nearest sample of the layer, 1 where none is covered. The layer's shading pass
// (deferred.frag COVERED) draws on the far plane against it with the test "greater",
// so only pixels with a surface run its shader: llvmpipe and lavapipe run a fullscreen
// pass's whole shader at every pixel, covered or not, and a GPU skips them early.
// FADE (the opaque layer, deferred.frag SKY): a surface in the fade band at the edge of
// the shown area (include/shade.glsl edge_fade) counts as none: the sky shows through it.
#include "include/common.glsl"
#ifdef FADE
#include "include/eye.glsl"
#endif

//@ sampler gdepth2D g_depth
//@ depth_write

void main() {
    ivec2 c = ivec2(gl_FragCoord.xy);
    float d = 1.0;
    for (int s = 0; s < SAMPLES; s++) d = min(d, FETCH(g_depth, c, s).r);
#ifdef FADE
    if (d < 1.0 && length(scene_pos(v_uv, d).xy - cam_pos.xy) > fade_start) d = 1.0;
#endif
    gl_FragDepth = d;
}
