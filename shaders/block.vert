// Block faces for the G-buffer, depth peeling and the shadow map (thesis §5.3.1).
// UNIFORM_ORIGIN: the GL 4.1 path (Geometry.indirect_ok off).
#include "include/vertex.glsl"
#include "include/frame.glsl"

//@ in uint in_v
//@ push vec3 region_origin     if UNIFORM_ORIGIN          // one draw per region (GL 4.1)
//@ in vec3 in_origin           if !defined(UNIFORM_ORIGIN) // per region, through baseInstance
//@ vary smooth vec3 g_world
//@ vary sample vec2 g_uv       if defined(MSAA_ALPHA) && SAMPLES > 1  // alpha test per sample (fig. 6.4)
//@ vary smooth vec2 g_uv       if !(defined(MSAA_ALPHA) && SAMPLES > 1)
//@ vary flat float g_layer
//@ vary flat vec3 g_normal
//@ vary flat uint g_quad

// Vertex animation (§5.3.1): 1 = wave the top (plants), 2 = all (leaves), 3 = water surface.
vec3 wave(vec3 p, uint anim, vec3 n) {
    float ph = time * 1.7 + p.x * 0.7 + p.y * 0.5;
    if (anim == 3u) return n.z > 0.5 ? p + vec3(0.0, 0.0, 0.05 * sin(ph) - 0.05) : p;
    // X/# planes list the top corners 2 and 3 (meshing's corner order)
    if (anim == 1u && (gl_VertexID & 3) < 2) return p;
    return p + vec3(0.06 * sin(ph), 0.05 * cos(ph * 1.3), 0.0);
}

void main() {
    Vertex v = decode(in_v);
#ifdef UNIFORM_ORIGIN
    vec3 p = v.position + region_origin;
#else
    vec3 p = v.position + in_origin;
#endif
    if (waving && v.anim != 0u) p = wave(p, v.anim, v.normal);
    g_world = p;
    g_uv = v.uv;
    g_layer = float(v.layer);
    g_normal = v.normal;
    g_quad = uint(gl_VertexID) >> 2;
    #ifdef SHADOW
    gl_Position = shadow_vp * vec4(p, 1.0);
#else
    gl_Position = vp * vec4(p, 1.0);
#endif
}
