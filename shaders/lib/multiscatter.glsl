// Multiple scattering's lobe (twin of explorer.physics.multiscatter_stack.lookup_rgb): one RGB table over
// (theta_i, theta_o) in air every COMPENSATION_STEP_DEG degrees (texel (theta_o, theta_i)), read with texelFetch
// and blended in float32, as the numpy twin does (by the including shader: a .brdf export inlines its table).
#include "generated/multiscatter.glsl"  // the constants shared with explorer/physics (generated at assembly)

void compensation_row(float theta, out int k, out float f) {
    float x = clamp(theta, 0.0, 0.5 * PI) / radians(COMPENSATION_STEP_DEG);
    k = min(int(floor(x)), COMPENSATION_ROWS - 2);
    f = x - float(k);
}

// The lobe table's cell of (i, o): rows ki (theta_i) and columns ko (theta_o), weights fi, fo; false where i or o
// is at or below the horizon. i, o: unit directions in the local frame (n = +z); polar angles by atan2, as the twin.
bool compensation_cell(vec3 i, vec3 o, out int ki, out float fi, out int ko, out float fo) {
    compensation_row(atan(length(i.xy), max(i.z, 0.0)), ki, fi);
    compensation_row(atan(length(o.xy), max(o.z, 0.0)), ko, fo);
    return i.z > 0.0 && o.z > 0.0;
}

// The compensation's weight by roughness (twin of explorer.physics.compensation.compensation_weight): 0 up to
// alpha = 0.4 (Eqs. 17 and 34 as published, the paper's validated range), 1 from 0.5, smoothstep between.
float compensation_weight(float alpha) {
    return smoothstep(COMPENSATION_FADE_START, COMPENSATION_FADE_END, alpha);
}
