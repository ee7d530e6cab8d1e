// What every pass reads of the frame: one std140 uniform block, written once per
// frame (voxel_addon/render/frame.py reads this declaration for the byte offsets, so
// this is the only place the layout is written down). Member types: float, int,
// bool, vec2, ivec2, vec3, vec4, mat4; a float after a vec3 shares its 16 bytes.
#ifndef FRAME_GLSL
#define FRAME_GLSL
layout(std140) uniform Frame {
    mat4 vp;               // the drawn camera (the culling view draws from above)
    mat4 inv_vp;
    mat4 shadow_vp;        // the light's view-projection: the shadow-map pass
    mat4 shadow_mat;       // world -> shadow-map texture coordinates and depth
    vec3 cam_pos;          float far_dist;
    vec3 shadow_eye;       float shadow_fade;  // the real camera; no shadow from there on
    vec3 day_ambient;      float day_u;        // eq. 4.1's daylight (light.daytime)
    vec3 day_direct;       float shadow_texel; // world size of one shadow-map texel
    vec3 sky_zenith;       float sky_stars;    // eq. 5.1
    vec3 sky_horizon;      float shadow_bias;  // depth units
    vec3 sky_halo;         float time;         // seconds: waving
    vec3 sky_disc;         float godray_strength;
    vec3 sky_light_dir;    bool waving;        // towards the sun by day, the moon by night
    vec2 sun_px;           float sun_radius;   bool sun_visible;  // the disc on screen, pixels
    float fog_start;       float fog_end;      float dof_start;   float dof_end;
    float ssao_radius;     // blocks
    vec3 cam_fwd;          bool ortho;         // orthographic: parallel rays along cam_fwd
};
#endif
