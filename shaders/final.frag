// Second global pass: mix in the distance blur by depth (§5.4.3), clamp to 8 bits.
// Defines: DOF.
#include "include/frame.glsl"
//@ sampler sampler2D sharp
//@ sampler sampler2D blurred  if DOF
//@ out 0 vec4 out_color

void main() {
    vec4 c = texture(sharp, v_uv);
#ifdef DOF
    vec4 b = texture(blurred, v_uv);
    c.rgb = mix(c.rgb, b.rgb, smoothstep(dof_start, dof_end, min(c.a, dof_end)));
#endif
    out_color = vec4(clamp(c.rgb, 0.0, 1.0), 1.0);
}
