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
// the physical sky (render/sky.py, include/atmosphere.glsl), haze, clouds, sea, fade
//@ frame vec4 sky_a[81]        // per node (SKY_NE elevations x SKY_NA azimuths from the
                                // sun): log of the sky's radiance but the sun's Mie scattering
//@ frame vec4 sky_b[81]        // log of the sun's Mie scattering there, without its phase
//@ frame vec3 sun_dir          // towards the sun
//@ frame float fog_density     // haze per block at sea level
//@ frame vec3 sky_pole         // the stars turn around it
//@ frame float fog_height      // haze 1/e per blocks of height
//@ frame vec3 cloud_sun        // light on the clouds: sun (or moon)
//@ frame float cloud_cover     // 0..1
//@ frame vec3 cloud_sky        // and from the sky
//@ frame float cloud_z         // height of the layer
//@ frame vec2 cloud_drift      // blocks
//@ frame float sea_z           // the sea's top
//@ frame float star_px         // a pixel (radians)
//@ frame vec4 area_box         // x0, y0, x1, y1 of the shown area (blocks): the sea is beyond it
//@ frame float fade_start      // horizontal distance: surfaces fade to the sky
//@ frame float fade_end
//@ frame int display           // 0 raw (debug views), 1 sRGB, 2 AgX-like tone curve (tonemap.glsl)
//@ frame bool clouds
//@ frame bool cloud_shadows
//@ frame bool sea
//@ frame bool water_fx
//@ frame bool walls            // close the shown area's outer wall (include/walls.glsl)
//@ frame int wall_layer        // its texture (stone's, in the block textures)
//@ frame bool ssr              // water reflects the scene on screen (include/ssr.glsl)
//@ frame bool starry           // stars are out (sky_stars > 0): the programs are built for it
//@ frame bool far_water        // far terrain drawn with water_fx: its water is opaque (shade.glsl)
//@ frame mat4 far_inv_vp        // far terrain's projection, inverted (render/far.py)
//@ frame float far_split        // 0: one depth range; 0.5: far terrain's depths from here on
//@ frame float sea_from        // the sea covers what is below it only this far out (far terrain)
