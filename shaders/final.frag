// Second global pass: mix in the distance blur by depth (§5.4.3), then from linear
// light to display values (include/final.glsl; include/tonemap.glsl: AgX-like, sRGB,
// or raw for debug). Defines: DOF.
//@ sampler sampler2D sharp
//@ sampler sampler2D blurred  if DOF
//@ out 0 vec4 out_color
#include "include/final.glsl"

void main() {
    out_color = vec4(final_color(v_uv), 1.0);
}
