// Screen-space ambient occlusion (§5.4.2): 2–8 samples by distance in the normal
// hemisphere on a spiral, compared against the front distance buffer.
#include "include/eye.glsl"
//@ sampler sampler2D front
//@ out 0 vec4 out_ao

void main() {
    vec4 f = texture(front, v_uv);
    if (f.r > 1e8) { out_ao = vec4(1.0); return; }
    vec3 p = ray_at(v_uv, f.r);
    vec3 n = normalize(f.yzw);
    vec3 t = normalize(abs(n.z) < 0.9 ? cross(n, vec3(0, 0, 1)) : cross(n, vec3(1, 0, 0)));
    vec3 b = cross(n, t);
    int count = int(mix(8.0, 2.0, clamp(f.r / (0.5 * far_dist), 0.0, 1.0)));
    float rot = fract(sin(dot(gl_FragCoord.xy, vec2(12.9898, 78.233))) * 43758.5453) * 6.2832;
    float occ = 0.0;
    for (int i = 0; i < 8; i++) {
        if (i >= count) break;
        float k = (float(i) + 0.5) / float(count);
        float a = rot + k * 12.566;
        vec3 s = p + n * 0.05 + (t * cos(a) * k + b * sin(a) * k + n * (1.0 - k) * 0.7) * ssao_radius;
        vec4 c = vp * vec4(s, 1.0);
        vec2 uv = c.xy / c.w * 0.5 + 0.5;
        float sd = texture(front, uv).r;
        float d = eye_dist(s);
        if (sd < d - 0.02 && d - sd < ssao_radius * 2.0) occ += 1.0;
    }
    out_ao = vec4(1.0 - 0.8 * occ / float(count));
}
