// The slice view: BRDF Explorer's image slice (src/shaderTemplates/brdftemplateImageSlice.frag) with
// phi_h = 0 and phi_d = 90 deg (or slice_phi_d). N = (0, 0, 1), X = (1, 0, 0), Y = (0, 1, 0); column i has
// theta_h = 90 deg (i + 0.5) / W, row j from the top has theta_d = 90 deg (j + 0.5) / H (BRDF Explorer puts
// theta_d = 0 at the bottom). As there, D = (theta_d, phi_d) is rotated about Y by theta_h and about N by
// phi_h into L, and V is L reflected about H = (theta_h, phi_h); the pixel is view_brdf(L, V, N, X, Y)
// (lib/views.glsl: non-finite channels 0), no cosine. At phi_d = 90 deg, L.z = V.z = cos(theta_h) cos(theta_d) > 0: both stay above the horizon.
// Twin: explorer.views.render.render_numpy(model, 'slice', ...).
#include "lib/views.glsl"

uniform vec2 resolution;
out vec4 frag_colour;

const float SLICE_PHI_H = 0.0;
// phi_d (radians): 90 deg unless the app's Slice window sets it (explorer.gpu.renderer.VIEW_UNIFORM_DEFAULTS
// binds 90 deg to every draw that does not, so a program shared with the app never keeps another value).
uniform float slice_phi_d = 1.5707963267948966;

// Rodrigues' rotation of v about the unit axis by angle (BRDF Explorer's rotate_vector).
vec3 slice_rotate(vec3 v, vec3 axis, float angle) {
    vec3 n = axis * dot(axis, v);
    return n + cos(angle) * (v - n) + sin(angle) * cross(axis, v);
}

void main() {
    vec3 normal = vec3(0.0, 0.0, 1.0);
    vec3 tangent = vec3(1.0, 0.0, 0.0);
    vec3 bitangent = vec3(0.0, 1.0, 0.0);
    float theta_h = radians(90.0) * gl_FragCoord.x / resolution.x;                   // x = i + 0.5
    float theta_d = radians(90.0) * (resolution.y - gl_FragCoord.y) / resolution.y;  // H - y = j + 0.5
    vec3 half_vector = vec3(sin(theta_h) * cos(SLICE_PHI_H), sin(theta_h) * sin(SLICE_PHI_H), cos(theta_h));
    vec3 difference = vec3(sin(theta_d) * cos(slice_phi_d), sin(theta_d) * sin(slice_phi_d), cos(theta_d));
    vec3 light = slice_rotate(slice_rotate(difference, bitangent, theta_h), normal, SLICE_PHI_H);
    vec3 view = 2.0 * dot(half_vector, light) * half_vector - light;
    frag_colour = vec4(view_brdf(light, view, normal, tangent, bitangent), 1.0);
}
