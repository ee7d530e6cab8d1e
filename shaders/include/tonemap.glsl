// From the scene's linear light to display values (final.frag): `display` 2 is an
// AgX-like tone curve (the look of Blender's default view transform: a log encoding
// over 16.5 stops, a sigmoid, highlights that go to white instead of clipping per
// channel; the polynomial fit and matrices are Benjamin Wrensch's "Minimal AgX"), 1 the
// sRGB transfer function with clipping, 0 the values as they are (debug views).
#ifndef TONEMAP_GLSL
#define TONEMAP_GLSL
#include "include/common.glsl"

// the textures are sRGB-encoded: their linear reflectance (a fast power law)
vec3 srgb_decode(vec3 c) { return pow(c, vec3(2.2)); }

vec3 agx(vec3 c) {
    const mat3 inset = mat3(0.842479062253094, 0.0423282422610123, 0.0423756549057051,
                            0.0784335999999992, 0.878468636469772, 0.0784336,
                            0.0792237451477643, 0.0791661274605434, 0.879142973793104);
    const mat3 outset = mat3(1.19687900512017, -0.0528968517574562, -0.0529716355144438,
                             -0.0980208811401368, 1.15190312990417, -0.0980434501171241,
                             -0.0990297440797205, -0.0989611768448433, 1.15107367264116);
    const float lo = -12.47393, hi = 4.026069;
    c = inset * max(c, vec3(0.0));
    c = (clamp(log2(max(c, vec3(1e-10))), lo, hi) - lo) / (hi - lo);
    vec3 x2 = c * c, x4 = x2 * x2;
    c = 15.5 * x4 * x2 - 40.14 * x4 * c + 31.96 * x4 - 6.868 * x2 * c + 0.4298 * x2
      + 0.1191 * c - 0.00232;
    // a look between AgX's base and "punchy": a little more contrast and colour
    float luma = dot(c, vec3(0.2126, 0.7152, 0.0722));
    c = pow(max(c, vec3(0.0)), vec3(1.12));
    c = luma + 1.25 * (c - luma);
    return clamp(outset * c, 0.0, 1.0);  // display-encoded already
}

vec3 to_display(vec3 c, int mode) {
    if (mode == 2) return agx(c);
    if (mode == 1) return srgb_encode(min(c, vec3(1.0)));
    return clamp(c, 0.0, 1.0);
}
#endif
