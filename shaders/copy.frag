// A texture copied texel for texel into a target of its size: how a device that cannot
// write part of a texture fills one layer of an array (the light volume's chunks,
// blender/liveview/device.py).
//@ sampler sampler2D src
//@ out 0 vec4 out_color

void main() {
    out_color = texelFetch(src, ivec2(gl_FragCoord.xy), 0);
}
