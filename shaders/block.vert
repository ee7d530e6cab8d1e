// Block faces for the G-buffer, depth peeling and the shadow map (thesis §5.3.1).
// One draw per batch of chunks (render/geometry.py): in_v.x is the packed vertex
// (include/vertex.glsl), in_v.y where its render region lies in the batch (bits 0-1
// chunk x, 2-3 chunk y, 4-11 region) and, in bits 16-31, the colour of a `color`
// block (its index into the world's palette, meshing.ChunkMesh.colors; 0 white).
#include "include/vertex.glsl"
#include "include/frame.glsl"

//@ in uvec2 in_v
//@ push vec4 batch_origin     // xyz: the batch's first block, w: the region height
//@ vary smooth vec3 g_world
//@ vary sample vec2 g_uv       if defined(MSAA_ALPHA) && SAMPLES > 1  // alpha test per sample (fig. 6.4)
//@ vary smooth vec2 g_uv       if !(defined(MSAA_ALPHA) && SAMPLES > 1)
//@ vary flat float g_layer
//@ vary flat vec3 g_normal
//@ vary flat uint g_quad
//@ vary flat uint g_color

// Vertex animation (§5.3.1): 1 = wave the top (plants), 2 = all (leaves), 3 = water surface.
vec3 wave(vec3 p, uint anim, vec3 n) {
    float ph = time * 1.7 + p.x * 0.7 + p.y * 0.5;
    if (anim == 3u) return n.z > 0.5 ? p + vec3(0.0, 0.0, 0.05 * sin(ph) - 0.05) : p;
    // X/# planes list the top corners 2 and 3 (meshing's corner order)
    if (anim == 1u && (gl_VertexID & 3) < 2) return p;
    return p + vec3(0.06 * sin(ph), 0.05 * cos(ph * 1.3), 0.0);
}

void main() {
    Vertex v = decode(in_v.x);
    uint o = in_v.y;
    vec3 p = v.position + batch_origin.xyz
           + vec3(float(o & 3u) * 16.0, float((o >> 2) & 3u) * 16.0, float((o >> 4) & 255u) * batch_origin.w);
    if (waving && v.anim != 0u) p = wave(p, v.anim, v.normal);
    g_world = p;
    g_uv = v.uv;
    g_layer = float(v.layer);
    g_normal = v.normal;
    g_quad = uint(gl_VertexID) >> 2;
    g_color = in_v.y >> 16;
    #ifdef SHADOW
    gl_Position = shadow_vp * vec4(p, 1.0);
#else
    gl_Position = vp * vec4(p, 1.0);
#endif
}
