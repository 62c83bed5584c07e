// The directional albedo plot: column i at theta_i = 90 (i + 0.5) / W degrees (the light in the xz plane),
// the BRDF x cos theta_o integrated over the outgoing hemisphere on the half-vector quadrature of
// explorer.views.albedo.half_vector_quadrature (Walter et al. 2007, Eq. 14: d omega_o = 4 (o.h) d omega_h):
// the host passes its theta_h nodes and weights (albedo_theta_h, albedo_d_theta) and the number of azimuths
// (midpoint rule), so both sides sum the same nodes. A material's Dirac reflection (HAS_MIRROR_REFLECTION,
// lib env.glsl's hook) adds its weight mirror_reflection(V, N); a pure Dirac (MIRROR_ONLY) integrates nothing
// else. Every row the same. Twin: explorer.views.albedo.albedo_numpy (explorer.views.plots.plot_numpy).
#include "lib/views.glsl"

#define ALBEDO_MAX_NODES 256
uniform vec2 resolution;
uniform int albedo_nodes;
uniform float albedo_theta_h[ALBEDO_MAX_NODES];
uniform float albedo_d_theta[ALBEDO_MAX_NODES];
uniform int albedo_phi_nodes;
out vec4 frag_colour;

void main() {
    float theta_i = plot_column_angle(0.0, radians(90.0), resolution.x);
    vec3 N = vec3(0.0, 0.0, 1.0);
    vec3 incident = vec3(sin(theta_i), 0.0, cos(theta_i));
    vec3 albedo = vec3(0.0);
#ifdef HAS_MIRROR_REFLECTION
    albedo += finite_or_zero(mirror_reflection(incident, N));
#endif
#ifndef MIRROR_ONLY
    float d_phi = radians(360.0) / float(albedo_phi_nodes);
    for (int k = 0; k < albedo_nodes; ++k) {
        float theta_h = albedo_theta_h[k];
        float weight = 4.0 * sin(theta_h) * albedo_d_theta[k] * d_phi;
        for (int p = 0; p < albedo_phi_nodes; ++p) {
            vec3 h = unit_direction(theta_h, (float(p) + 0.5) * d_phi);
            float i_dot_h = dot(incident, h);
            vec3 o = 2.0 * i_dot_h * h - incident;
            if (i_dot_h > 0.0 && o.z > 0.0) {
                albedo += view_brdf(incident, o, N, vec3(1.0, 0.0, 0.0), vec3(0.0, 1.0, 0.0)) * (o.z * weight * i_dot_h);
            }
        }
    }
#endif
    frag_colour = vec4(albedo, 1.0);
}
