// BRDF Explorer's "theta H" plot: column i at theta_h = 90 (i + 0.5) / W degrees, at theta_d = plot_theta_d,
// phi_h = 0, phi_d = 90 degrees (the slice view's construction); every row the same. The pixel is
// view_brdf(L, V, N, X, Y) (lib/views.glsl's rule). Twin: explorer.views.plots.plot_numpy.
#include "lib/views.glsl"

uniform vec2 resolution;
uniform float plot_theta_d;
out vec4 frag_colour;

void main() {
    vec3 L, V;
    rusinkiewicz_directions(plot_column_angle(0.0, radians(90.0), resolution.x), plot_theta_d, radians(90.0), L, V);
    frag_colour = vec4(view_brdf(L, V, vec3(0.0, 0.0, 1.0), vec3(1.0, 0.0, 0.0), vec3(0.0, 1.0, 0.0)), 1.0);
}
