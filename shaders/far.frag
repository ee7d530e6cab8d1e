// Far terrain into the G-buffer (far.vert): nothing where chunks are drawn (the near
// mask: no double surfaces; near chunks end where the far ring begins, so no crack)
// and nothing beyond the far distance (fog_end: the sky starts there). Albedo stays
// sRGB-encoded like the chunks' (shade.glsl decodes); water is marked as block.frag does.
#include "include/frame.glsl"

//@ sampler sampler2D near_mask  // per chunk of near_box: 1 where it is drawn as chunks
//@ push vec4 near_box           // xy: the mask's first chunk, zw: its size in chunks
//@ out 0 vec4 out_albedo
//@ out 1 vec4 out_normal

// the light levels a block of water takes (core.blocks: water's attenuation; a test
// holds the two equal)
#define WATER_LEVELS 2.0

// The sky light a floor gets under water d blocks deep (water face to the floor's
// top face), as the near floor there is lit: its top face sees the water voxel above
// it, 15 less WATER_LEVELS per block of water, squared as include/shade.glsl does
// (far/mesh.py _under_water is the twin). Only where the chunks beside the point are
// lit exactly (inside the light window): beyond it the near floor gets open daylight
// (include/lightvol.glsl), and the far floor must look as the near one beside it.
float under_water(float d) {
    vec2 lo = near_box.xy * 16.0, hi = lo + max(near_box.zw * 16.0, vec2(1.0));
    vec2 q = clamp(f_world.xy, lo, hi - 0.5);
    if (near_box.z > 0.0 && (any(lessThan(q, vec2(vol_lo))) || any(greaterThanEqual(q, vec2(vol_hi)))))
        return 1.0;
    float n = max(floor(d + 0.5), 0.0);
    return pow(max(15.0 - WATER_LEVELS * n, 0.0) / 15.0, 2.2);
}

// Whether world point p lies on a chunk that is drawn (tested a twentieth of a block
// further from the eye: a far pixel on the chunks' edge, its position interpolated a
// little inside, was dropped though the chunks' face ends there: a crack along the
// seam, the far floor seen without its water).
bool on_chunks(vec2 p) {
    vec2 at = p + 0.05 * normalize(p - cam_pos.xy + vec2(1e-6, 0.0));
    ivec2 c = ivec2(floor(at / 16.0) - near_box.xy);
    return all(greaterThanEqual(c, ivec2(0))) && all(lessThan(c, ivec2(near_box.zw)))
        && texelFetch(near_mask, c, 0).r > 0.5;
}

void main() {
    if (distance(f_world.xy, cam_pos.xy) > fog_end) discard;
#if SAMPLES > 1
    // Under MSAA the fragment runs once per pixel, for all its samples. Dropped by its
    // centre, a pixel on the edge lost its samples outside the chunks (nothing drew
    // there: the far floor without its water, a dark dot). Dropped per sample, an edge
    // pixel was half near water over its (dark, deep) floor and half far water: the
    // water layer, composited over the pixel's mean opaque colour, darkened it (a
    // dotted line). So a pixel with any sample off the chunks keeps all of them: the
    // near water over far water there gives way to it (block.frag), the pixel is far
    // water as a whole, and the near chunks' opaque surfaces are in front anyway
    // (the near half of the depth range).
    bool off = false;
    for (int i = 0; i < SAMPLES; i++)
        off = off || !on_chunks(interpolateAtSample(f_world, i).xy);
    if (!off) discard;
#else
    if (on_chunks(f_world.xy)) discard;
#endif
    vec3 albedo = f_albedo;
    if (f_water < 0.5 && f_under.y > 0.0) {  // ground under water: seen through near water
        float d = f_under.x / f_under.y - f_world.z;
        if (d > 0.0) albedo *= pow(under_water(d), 1.0 / 2.2);
    }
    if (f_water > 0.5) {
        // as a near water layer over its floor (block.frag's water_body, the depth
        // along the view ray to the floor; far/mesh.py water_over is the twin):
        // linear, then encoded again like the chunks' albedo
        float s = f_body.a / max(normalize(cam_pos - f_world).z, 0.02);
        float k = 1.0 - exp(-s * 0.25);
        vec3 f = mix(vec3(0.5, 0.6, 0.5), vec3(0.08, 0.2, 0.16), k);
        float a = mix(0.3, 0.95, k);
        vec3 lin = pow(f_albedo, vec3(2.2)) * under_water(f_body.a) * (1.0 - a)
                 + pow(f_body.rgb, vec3(2.2)) * f * a;
        albedo = pow(lin, vec3(1.0 / 2.2));
    }
    out_albedo = vec4(albedo, 1.0);
    out_normal = vec4(normalize(f_normal) * 0.5 + 0.5, f_water);  // (glow: water's mark)
}
