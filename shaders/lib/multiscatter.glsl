// Multiple scattering's lobe (twin of explorer.physics.multiscatter_stack.lookup_rgb): one RGB table over
// (theta_i, theta_o) in air every COMPENSATION_STEP_DEG degrees (texel (theta_o, theta_i)), read with texelFetch
// and blended here in float32, as the numpy twin does.
#include "generated/multiscatter.glsl"  // the constants shared with explorer/physics (generated at assembly)

void compensation_row(float theta, out int k, out float f) {
    float x = clamp(theta, 0.0, 0.5 * PI) / radians(COMPENSATION_STEP_DEG);
    k = min(int(floor(x)), COMPENSATION_ROWS - 2);
    f = x - float(k);
}

// i, o: unit directions in the local frame (n = +z); 0 where either is at or below the horizon.
vec3 compensation_lobe(vec3 i, vec3 o, sampler2D lobe_table) {
    if (i.z <= 0.0 || o.z <= 0.0) return vec3(0.0);
    int ki, ko;
    float fi, fo;
    compensation_row(atan(length(i.xy), i.z), ki, fi);  // polar angles by atan2, as the twin
    compensation_row(atan(length(o.xy), o.z), ko, fo);
    vec3 low = mix(texelFetch(lobe_table, ivec2(ko, ki), 0).rgb, texelFetch(lobe_table, ivec2(ko + 1, ki), 0).rgb, fo);
    vec3 high = mix(texelFetch(lobe_table, ivec2(ko, ki + 1), 0).rgb, texelFetch(lobe_table, ivec2(ko + 1, ki + 1), 0).rgb, fo);
    return mix(low, high, fi);
}
