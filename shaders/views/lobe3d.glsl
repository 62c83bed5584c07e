// BRDF Explorer's 3D lobe, as the radius in every outgoing direction: column i at phi_o = 360 (i + 0.5) / W,
// row j (from the top) at theta_o = 90 (j + 0.5) / H degrees, the light at light_direction. The pixel is
// view_brdf(L, V, N, X, Y) (lib/views.glsl's rule); the host draws the surface of radius (plotted) value.
// Twin: explorer.views.plots.plot_numpy.
#include "lib/views.glsl"

uniform vec2 resolution;
uniform vec3 light_direction;
out vec4 frag_colour;

void main() {
    float phi_o = plot_column_angle(0.0, radians(360.0), resolution.x);
    float theta_o = radians(90.0) * (resolution.y - gl_FragCoord.y) / resolution.y;  // rows from the top
    vec3 view = unit_direction(theta_o, phi_o);
    frag_colour = vec4(view_brdf(light_direction, view, vec3(0.0, 0.0, 1.0), vec3(1.0, 0.0, 0.0), vec3(0.0, 1.0, 0.0)), 1.0);
}
