// Separable 9-tap Gaussian. BILATERAL: the distance blur of §5.4.3 (σ 2, samples
// weighted down across depth edges; alpha carries distance). Otherwise the SSAO
// blur (σ 3, 9x9 over two passes). VERTICAL: the second pass.
//@ sampler sampler2D src
//@ out 0 vec4 out_color
#ifdef VERTICAL
const vec2 step_px = vec2(0.0, 1.0);
#else
const vec2 step_px = vec2(1.0, 0.0);
#endif
void main() {
#ifdef BILATERAL
    const float sigma = 2.0;
#else
    const float sigma = 3.0;
#endif
    vec2 px = step_px / vec2(textureSize(src, 0));
    vec4 c0 = texture(src, v_uv);
    vec4 acc = vec4(0.0);
    float wsum = 0.0;
    for (int i = -4; i <= 4; i++) {
        vec4 c = texture(src, v_uv + px * float(i));
        float w = exp(-float(i * i) / (2.0 * sigma * sigma));
#ifdef BILATERAL
        // keep near objects from bleeding into far ones
        w *= c.a >= c0.a * 0.8 ? 1.0 : 0.05;
#endif
        acc += c * w;
        wsum += w;
    }
#ifdef BILATERAL
    out_color = vec4(acc.rgb / wsum, c0.a);
#else
    out_color = acc / wsum;
#endif
}
