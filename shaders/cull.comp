// GPU twin of render/camera.py visible_boxes (the NumPy version is the reference;
// tests/render compare them): one invocation per indirect draw command, whose
// instanceCount becomes 1 when its region's box may intersect the clip volume and 0
// when all of the box lies outside one clip plane. The draws then skip culled
// regions without the CPU gathering commands each frame (GL 4.3+).
layout(local_size_x = 64) in;

struct Command { uint count; uint instances; uint first; uint base_vertex; uint base_instance; };
layout(std430, binding = 0) buffer Commands { Command cmd[]; };
layout(std430, binding = 1) readonly buffer Boxes { vec4 box[]; };  // per region: centre, half

uniform vec4 planes[6];  // camera.planes(mvp): inside where dot(xyz, p) + w >= 0
uniform uint n;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= n) return;
    uint row = cmd[i].base_instance;
    vec3 c = box[2u * row].xyz;
    vec3 h = box[2u * row + 1u].xyz;
    bool vis = true;
    for (int k = 0; k < 6; k++)
        vis = vis && dot(planes[k].xyz, c) + dot(abs(planes[k].xyz), h) + planes[k].w >= 0.0;
    cmd[i].instances = vis && cmd[i].count > 0u ? 1u : 0u;  // count 0: a removed chunk's hole
}
