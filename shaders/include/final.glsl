// The final pass's colour (final.frag, and the live view's composite that folds it in:
// viewport.frag with FOLD): the distance blur mixed in by depth (§5.4.3), then from
// linear light to display values. The includer declares `sharp` and, with DOF, `blurred`.
#ifndef FINAL_GLSL
#define FINAL_GLSL
#include "include/frame.glsl"
#include "include/tonemap.glsl"

vec3 final_color(vec2 uv) {
    vec4 c = texture(sharp, uv);
#ifdef DOF
    vec4 b = texture(blurred, uv);
    // not the sky: its stars and clouds are not in the haze (its distance, 1e9, is
    // the half float's largest value in this target, or inf)
    if (c.a < 6e4) c.rgb = mix(c.rgb, b.rgb, smoothstep(dof_start, dof_end, min(c.a, dof_end)));
#endif
    return to_display(c.rgb, display);
}
#endif
