// BRDF Explorer's "theta V" plot: column i at theta_v = -90 + 180 (i + 0.5) / W degrees, V in the plane of
// azimuth plot_phi_v (a negative theta_v lies at phi_v + 180), the light at light_direction; every row the
// same. The pixel is view_brdf(L, V, N, X, Y) (lib/views.glsl's rule), N, X, Y the z, x and y axes; what is
// plotted of it (N.L, channel, log) is the host's. Twin: explorer.views.plots.plot_numpy.
#include "lib/views.glsl"

uniform vec2 resolution;
uniform vec3 light_direction;
uniform float plot_phi_v;
out vec4 frag_colour;

void main() {
    float theta_v = plot_column_angle(radians(-90.0), radians(180.0), resolution.x);
    vec3 view = unit_direction(theta_v, plot_phi_v);
    frag_colour = vec4(view_brdf(light_direction, view, vec3(0.0, 0.0, 1.0), vec3(1.0, 0.0, 0.0), vec3(0.0, 1.0, 0.0)), 1.0);
}
