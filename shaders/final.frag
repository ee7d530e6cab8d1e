// Second global pass: mix in the distance blur by depth (§5.4.3), then from linear
// light to display values (include/tonemap.glsl: AgX-like, sRGB, or raw for debug).
// Defines: DOF.
#include "include/frame.glsl"
#include "include/tonemap.glsl"
//@ sampler sampler2D sharp
//@ sampler sampler2D blurred  if DOF
//@ out 0 vec4 out_color

void main() {
    vec4 c = texture(sharp, v_uv);
#ifdef DOF
    vec4 b = texture(blurred, v_uv);
    // not the sky: its stars and clouds are not in the haze (its distance, 1e9, is
    // the half float's largest value in this target, or inf)
    if (c.a < 6e4) c.rgb = mix(c.rgb, b.rgb, smoothstep(dof_start, dof_end, min(c.a, dof_end)));
#endif
    out_color = vec4(to_display(c.rgb, display), 1.0);
}
