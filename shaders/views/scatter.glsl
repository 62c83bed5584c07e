// The scatter view: the scatterogram of the paper's Figure 9, light from light_direction (unit, toward the
// light). Pixel (i, j), j from the top, lies at p = (2 (i + 0.5) / W - 1, 1 - 2 (j + 0.5) / H); inside the
// disc |p| < 1 it shows the outgoing direction V at theta_o = 90 deg |p| and azimuth phi_o of p (+x to the
// right, +y up), N = (0, 0, 1), X = (1, 0, 0), Y = (0, 1, 0); the pixel is view_brdf(L, V, N, X, Y) cos(theta_o)
// (lib/views.glsl: 0 for a light below the horizon, non-finite channels 0), outside 0. The 5, 30, 60 and 90 deg circles are drawn by the host on PNG output only.
// Twin: explorer.views.render.render_numpy(model, 'scatter', ...).
#include "lib/views.glsl"

uniform vec2 resolution;
uniform vec3 light_direction;
out vec4 frag_colour;

void main() {
    vec2 p;
    float r2;
    if (!disc_point(resolution, p, r2)) {
        frag_colour = vec4(0.0, 0.0, 0.0, 1.0);
        return;
    }
    float r = sqrt(r2);
    vec2 azimuth = r > 0.0 ? p / r : vec2(1.0, 0.0);  // (cos phi_o, sin phi_o)
    float theta_o = radians(90.0) * r;
    vec3 view = vec3(sin(theta_o) * azimuth, cos(theta_o));
    vec3 normal = vec3(0.0, 0.0, 1.0);
    vec3 tangent = vec3(1.0, 0.0, 0.0);
    vec3 bitangent = vec3(0.0, 1.0, 0.0);
    frag_colour = vec4(view_brdf(light_direction, view, normal, tangent, bitangent) * view.z, 1.0);
}
