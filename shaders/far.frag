// Far terrain into the G-buffer (far.vert): nothing where chunks are drawn (the near
// mask: no double surfaces; near chunks end where the far ring begins, so no crack)
// and nothing beyond the far distance (fog_end: the sky starts there). Albedo stays
// sRGB-encoded like the chunks' (shade.glsl decodes); water is marked as block.frag does.
#include "include/frame.glsl"

//@ sampler sampler2D near_mask  // per chunk of near_box: 1 where it is drawn as chunks
//@ push vec4 near_box           // xy: the mask's first chunk, zw: its size in chunks
//@ out 0 vec4 out_albedo
//@ out 1 vec4 out_normal

void main() {
    if (distance(f_world.xy, cam_pos.xy) > fog_end) discard;
    ivec2 c = ivec2(floor(f_world.xy / 16.0) - near_box.xy);
    if (all(greaterThanEqual(c, ivec2(0))) && all(lessThan(c, ivec2(near_box.zw)))
            && texelFetch(near_mask, c, 0).r > 0.5)
        discard;
    out_albedo = vec4(f_albedo, 1.0);
    out_normal = vec4(normalize(f_normal) * 0.5 + 0.5, f_water);  // (glow: water's mark)
}
