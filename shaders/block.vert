// Block faces for the G-buffer, depth peeling and the shadow map (thesis §5.3.1).
#include "include/standin_vertex.glsl"

uniform mat4 mvp;
uniform float time;
uniform bool waving;

out vec3 g_world;
out vec2 g_uv;
flat out float g_layer;
flat out vec3 g_normal;
flat out uint g_quad;

// Vertex animation (§5.3.1): 1 = wave the top (plants), 2 = all (leaves), 3 = water surface.
vec3 wave(vec3 p, int anim) {
    if (!waving || anim == 0) return p;
    float ph = time * 1.7 + p.x * 0.7 + p.y * 0.5;
    if (anim == 3) return p + vec3(0.0, 0.0, 0.06 * sin(ph) - 0.1);
    return p + vec3(0.06 * sin(ph), 0.05 * cos(ph * 1.3), 0.0);
}

void main() {
    vec3 p = v_position();
    int anim = v_anim();
    // the top edge of a plant quad is where the texture's v is 1
    if (anim == 1) p = v_uv().y > 0.5 ? wave(p, 2) : p;
    else p = wave(p, anim);
    g_world = p;
    g_uv = v_uv();
    g_layer = v_layer();
    g_normal = v_normal();
    g_quad = v_quad();
    gl_Position = mvp * vec4(p, 1.0);
}
