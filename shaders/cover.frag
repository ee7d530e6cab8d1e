// A G-buffer's coverage as a one-sample depth buffer (fullscreen.vert): each pixel's
// nearest sample, 1 where none is covered (an MSAA peel layer's, the opaque layer's
// for the live view's two lighting passes). A lighting pass draws on the far plane
// against it, test "greater" (deferred.frag COVERED) or "lequal" (SKY), so only the
// pixels it is for run its shader: llvmpipe and lavapipe run a fullscreen pass's whole
// shader at every pixel, covered or not, and a GPU skips them early.
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
