// One triangle covering the screen; v_uv in [0, 1]. Defines: COVERED (on the far
// plane: a depth test "greater" passes only where the target's depth holds a surface).
//@ vary smooth vec2 v_uv
void main() {
    vec2 p = vec2(float((gl_VertexID & 1) << 2) - 1.0, float((gl_VertexID & 2) << 1) - 1.0);
    v_uv = p * 0.5 + 0.5;
#ifdef COVERED
    gl_Position = vec4(p, 1.0, 1.0);
#else
    gl_Position = vec4(p, 0.0, 1.0);
#endif
}
