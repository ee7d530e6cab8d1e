// One triangle covering the screen; v_uv in [0, 1]. Defines: COVERED, SKY (on the far
// plane, drawn against a coverage depth, cover.frag: test "greater" passes where the
// pixel has a surface, "lequal" where it has none).
//@ vary smooth vec2 v_uv
void main() {
    vec2 p = vec2(float((gl_VertexID & 1) << 2) - 1.0, float((gl_VertexID & 2) << 1) - 1.0);
    v_uv = p * 0.5 + 0.5;
#if defined(COVERED) || defined(SKY)
    gl_Position = vec4(p, 1.0, 1.0);
#else
    gl_Position = vec4(p, 0.0, 1.0);
#endif
}
