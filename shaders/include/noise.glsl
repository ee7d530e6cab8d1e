// The generators' hash and gradients (gpu/noise.h, voxel_addon/generation/noise.py) for
// the sky: 2D gradient noise whose corner gradients come from vx_hash2 instead of a
// permutation table (no table to upload), and fBm over it. The NumPy twin is
// voxel_addon/render/clouds.py (tests/render/test_clouds.py compares the two).
#ifndef NOISE_GLSL
#define NOISE_GLSL

uint vx_mix(uint h) {
    h ^= h >> 16; h *= 0x7feb352du;
    h ^= h >> 15; h *= 0x846ca68bu;
    h ^= h >> 16;
    return h;
}

uint vx_hash2(ivec2 p, uint s) { return vx_mix(uint(p.x) * 0x8da6b343u + uint(p.y) * 0xd8163841u + s); }

// noise.h's grad2: 8 directions (axes and diagonals)
float vx_grad2(uint h, vec2 p) {
    float a = (h & 1u) != 0u ? -p.x : p.x;
    float b = (h & 1u) != 0u ? -p.y : p.y;
    float c = (h & 2u) != 0u ? -p.y : p.y;
    return (h & 4u) != 0u ? (a + c) * 0.70710677 : ((h & 2u) != 0u ? b : a);
}

vec2 vx_fade(vec2 t) { return t * t * t * (t * (t * 6.0 - 15.0) + 10.0); }

// Gradient noise in about [-1, 1]
float gnoise2(vec2 p, uint s) {
    vec2 i = floor(p);
    vec2 f = p - i;
    ivec2 c = ivec2(i);
    vec2 u = vx_fade(f);
    float n00 = vx_grad2(vx_hash2(c, s), f);
    float n10 = vx_grad2(vx_hash2(c + ivec2(1, 0), s), f - vec2(1.0, 0.0));
    float n01 = vx_grad2(vx_hash2(c + ivec2(0, 1), s), f - vec2(0.0, 1.0));
    float n11 = vx_grad2(vx_hash2(c + ivec2(1, 1), s), f - vec2(1.0, 1.0));
    return mix(mix(n00, n10, u.x), mix(n01, n11, u.x), u.y);
}

// Sum of `n` octaves (lacunarity 2, gain 0.5; octave o has seed s + o), each octave
// rotated a little so the grids do not line up.
float fbm2(vec2 p, uint s, int n) {
    float sum = 0.0, a = 0.5;
    const mat2 rot = mat2(0.8, 0.6, -0.6, 0.8);
    for (int o = 0; o < 8; o++) {
        if (o >= n) break;
        sum += a * gnoise2(p, s + uint(o));
        p = rot * p * 2.0;
        a *= 0.5;
    }
    return sum;
}
#endif
