// Weighted blended OIT resolve (McGuire & Bavoil 2013, eq. 6) into one premultiplied
// layer, which composite.frag blends over the opaque image as its LAYERS=1 layer0.
// Per sample when the targets are multisampled (edges of the transparent surfaces
// against the opaque depth), then averaged. Defines: SAMPLES.
#include "include/common.glsl"

//@ sampler gsampler2D accum
//@ sampler gsampler2D reveal
//@ out 0 vec4 out_color

vec4 resolve(ivec2 c, int s) {
    vec4 a = FETCH(accum, c, s);
    float cover = 1.0 - exp(-FETCH(reveal, c, s).r);  // 1 - prod(1 - alpha)
    vec3 rgb = a.rgb;
    // an fp16 overflow (inf) keeps the hue as well as it can (the paper's fix)
    if (any(isinf(rgb))) rgb = vec3(a.a);
    return vec4(rgb / max(a.a, 1e-5), 1.0) * cover;
}

void main() {
    ivec2 c = ivec2(gl_FragCoord.xy);
    vec4 acc = vec4(0.0);
    for (int s = 0; s < SAMPLES; s++) acc += resolve(c, s);
    out_color = acc / float(SAMPLES);
}
