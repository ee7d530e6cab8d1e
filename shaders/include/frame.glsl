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
    // the physical sky (render/sky.py, include/atmosphere.glsl), haze, clouds, sea, fade
    vec4 sky_a[81];        // per node (SKY_NE elevations x SKY_NA azimuths from the sun):
                           // log of the sky's radiance but the sun's Mie scattering
    vec4 sky_b[81];        // log of the sun's Mie scattering there, without its phase
    vec3 sun_dir;          float fog_density;   // towards the sun; haze per block at sea level
    vec3 sky_pole;         float fog_height;    // the stars turn around it; haze 1/e per blocks
    vec3 cloud_sun;        float cloud_cover;   // light on the clouds: sun (or moon), 0..1 cover
    vec3 cloud_sky;        float cloud_z;       // and from the sky; height of the layer
    vec2 cloud_drift;      float sea_z;         float star_px;  // blocks; sea top; a pixel (rad)
    vec4 area_box;         // x0, y0, x1, y1 of the shown area (blocks): the sea is beyond it
    float fade_start;      float fade_end;      // horizontal distance: surfaces fade to the sky
    int display;           // 0 raw (debug views), 1 sRGB, 2 AgX-like tone curve (tonemap.glsl)
    bool clouds;           bool cloud_shadows;  bool sea;  bool water_fx;
};
#endif
