// Decoder for render/standin_mesh.py vertices (until the meshing package's format lands).
in vec3 in_pos;
in uint in_a;
in uint in_b;

vec3 v_position() { return in_pos; }
vec3 v_normal() {
    ivec3 n = ivec3(int(in_a << 24) >> 24, int(in_a << 16) >> 24, int(in_a << 8) >> 24);
    return vec3(n) / 127.0;
}
float v_layer() { return float(in_a >> 24); }
vec2 v_uv() { return vec2(float(in_b & 255u), float((in_b >> 8) & 255u)) / 16.0; }
int v_anim() { return int((in_b >> 16) & 15u); }
uint v_quad() { return in_b >> 20; }
