// A region's kept frame (viewport.frag with KEEP) into Blender's framebuffer: the
// same colour and depth the composite would write, depth tested LEQUAL by the
// caller, so Blender's objects still mix both ways while the pipeline is skipped.
#include "include/common.glsl"
//@ sampler sampler2D kept_color  // sRGB8_A8 (read back linear), alpha 0: nothing of ours here
//@ sampler sampler2D kept_depth  // R32F, Blender's depth
//@ push int srgbTarget           // set by Blender (include/common.glsl, to_target)
//@ out 0 vec4 out_color
//@ depth_write

void main() {
    ivec2 size = textureSize(kept_color, 0);
    ivec2 c = clamp(ivec2(v_uv * vec2(size)), ivec2(0), size - 1);
    vec4 col = texelFetch(kept_color, c, 0);
    if (col.a == 0.0) discard;
    gl_FragDepth = texelFetch(kept_depth, c, 0).r;
    // linear already (the texture is sRGB): as it is into an sRGB target, else encoded
    out_color = srgbTarget != 0 ? col : vec4(srgb_encode(col.rgb), col.a);
}
