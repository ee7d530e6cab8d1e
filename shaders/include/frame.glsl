// What every pass reads of the frame: one uniform block, written once per frame
// (voxel_addon/render/frame.py packs it by render/glsl.py's frame_layout, which reads
// these lines: this is the only place the members are written down). Member types:
// float, int, bool, vec2, ivec2, vec3, vec4, mat4; bodies read them by name.
//@ frame mat4 vp               // the drawn camera (the culling view draws from above)
//@ frame mat4 inv_vp
//@ frame mat4 shadow_vp        // the light's view-projection: the shadow-map pass
//@ frame mat4 shadow_mat       // world -> shadow-map texture coordinates and depth
//@ frame vec3 cam_pos
//@ frame float far_dist
//@ frame vec3 shadow_eye       // the real camera; no shadow from shadow_fade on
//@ frame float shadow_fade
//@ frame vec3 day_ambient      // eq. 4.1's daylight (light.daytime)
//@ frame float day_u
//@ frame vec3 day_direct
//@ frame float shadow_texel    // world size of one shadow-map texel
//@ frame vec3 sky_zenith       // eq. 5.1
//@ frame float sky_stars
//@ frame vec3 sky_horizon
//@ frame float shadow_bias     // depth units
//@ frame vec3 sky_halo
//@ frame float time            // seconds: waving
//@ frame vec3 sky_disc
//@ frame float godray_strength
//@ frame vec3 sky_light_dir    // towards the sun by day, the moon by night
//@ frame bool waving
//@ frame vec2 sun_px           // the disc on screen, pixels
//@ frame float sun_radius
//@ frame bool sun_visible
//@ frame float fog_start
//@ frame float fog_end
//@ frame float dof_start
//@ frame float dof_end
//@ frame float ssao_radius     // blocks
//@ frame vec3 cam_fwd          // orthographic: parallel rays along cam_fwd
//@ frame bool ortho
//@ frame int vol_n             // the light volume (include/lightvol.glsl): slots per side
//@ frame ivec2 vol_lo          // its resident box, in blocks
//@ frame ivec2 vol_hi
//@ frame mat4 far_inv_vp        // far terrain's projection, inverted (render/far.py)
//@ frame float far_split        // 0: one depth range; 0.5: far terrain's depths from here on
