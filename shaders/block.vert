// Block faces for the G-buffer, depth peeling and the shadow map (thesis §5.3.1).
// One draw per batch of chunks (render/geometry.py): in_v.x is the packed vertex
// (include/vertex.glsl), in_v.y where its render region lies in the batch (bits 0-1
// chunk x, 2-3 chunk y, 4-11 region) and, in bits 16-31, the colour of a `color`
// block (its index into the world's palette, meshing.ChunkMesh.colors; 0 white).
#include "include/vertex.glsl"
#include "include/frame.glsl"

//@ in uvec2 in_v                if !defined(MODEL)
//@ in uvec4 in_f                if MODEL  // a model quad's vertex (render/models.py)
//@ push vec4 batch_origin     // xyz: the batch's first block, w: the region height
//@ vary smooth vec3 g_world
//@ vary sample vec2 g_uv       if defined(MSAA_ALPHA) && SAMPLES > 1  // alpha test per sample (fig. 6.4)
//@ vary smooth vec2 g_uv       if !(defined(MSAA_ALPHA) && SAMPLES > 1)
//@ vary flat float g_layer
//@ vary flat vec3 g_normal
//@ vary flat uint g_quad
//@ vary flat uint g_color
//@ vary flat vec3 g_tint      if MODEL   // the biome's or the block's colour (sRGB)

// Vertex animation (§5.3.1): 1 = wave the top (plants), 2 = all (leaves), 3 = water surface.
vec3 wave(vec3 p, uint anim, vec3 n) {
    float ph = time * 1.7 + p.x * 0.7 + p.y * 0.5;
    // (water: none on a chunk's border, where far terrain's flat water meets the
    // chunks at the top face: a dip there let a grazing ray pass between the two)
    if (anim == 3u) return n.z > 0.5 && all(notEqual(fract(p.xy / 16.0), vec2(0.0)))
        ? p + vec3(0.0, 0.0, 0.05 * sin(ph) - 0.05) : p;
    // X/# planes list the top corners 2 and 3 (meshing's corner order)
    if (anim == 1u && (gl_VertexID & 3) < 2) return p;
    return p + vec3(0.06 * sin(ph), 0.05 * cos(ph * 1.3), 0.0);
}

#ifdef MODEL
vec3 oct_normal(uint e) {
    vec2 f = vec2(float(e & 31u), float((e >> 5) & 31u)) / 15.0 - 1.0;
    vec3 n = vec3(f, 1.0 - abs(f.x) - abs(f.y));
    if (n.z < 0.0) n.xy = (1.0 - abs(n.yx)) * vec2(n.x >= 0.0 ? 1.0 : -1.0, n.y >= 0.0 ? 1.0 : -1.0);
    return normalize(n);
}

#endif

void main() {
#ifdef MODEL  // a Minecraft model quad: batch_origin is its chunk's corner
    vec3 p = batch_origin.xyz - 16.0 + vec3(float(in_f.x & 65535u) / 1024.0,
        float(in_f.x >> 16) / 1024.0, float(in_f.y & 4194303u) / 8192.0);
    g_uv = vec2(float(in_f.z & 2047u), float((in_f.z >> 11) & 2047u)) / 2047.0;
    g_layer = float(in_f.y >> 22);
    g_normal = oct_normal(in_f.z >> 22);
    g_color = 0u;
    g_tint = vec3(float(in_f.w & 255u), float((in_f.w >> 8) & 255u), float((in_f.w >> 16) & 255u)) / 255.0;
#else
    Vertex v = decode(in_v.x);
    uint o = in_v.y;
    vec3 p = v.position + batch_origin.xyz
           + vec3(float(o & 3u) * 16.0, float((o >> 2) & 3u) * 16.0, float((o >> 4) & 255u) * batch_origin.w);
    if (waving && v.anim != 0u) p = wave(p, v.anim, v.normal);
    g_uv = v.uv;
    g_layer = float(v.layer);
    g_normal = v.normal;
    g_color = in_v.y >> 16;
#endif
    g_world = p;
    g_quad = uint(gl_VertexID) >> 2;
#ifdef SHADOW
    gl_Position = shadow_vp * vec4(p, 1.0);
#else
    gl_Position = vp * vec4(p, 1.0);
#endif
}
