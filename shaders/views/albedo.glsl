// The directional albedo's terms: the BRDF x cos theta_o on the half-vector quadrature of
// explorer.views.albedo.half_vector_quadrature (Walter et al. 2007, Eq. 14: d omega_o = 4 (o.h) d omega_h),
// one node a fragment; the host sums each incidence angle's terms in float64 (explorer.gpu.Renderer.render,
// explorer.views.albedo.sum_albedo_terms). One BRDF call a fragment, as in every other view: a fragment that
// summed a whole hemisphere would call a spectral BRDF 16384 times, and llvmpipe ends a fragment's loops
// after 65535 iterations in all (the sum then stops early, silently).
//
// Layout (rows from the top): column p is the azimuth (p + 0.5) d_phi, row r = c albedo_nodes + k the
// theta_h node k (albedo_theta_h, albedo_d_theta: the host's nodes and weights) of incidence column
// albedo_first_column + c of a curve albedo_columns wide (theta_i = 90 (column + 0.5) / albedo_columns
// degrees, the light in the xz plane). A material's Dirac reflection (HAS_MIRROR_REFLECTION, lib env.glsl's
// hook) adds its weight mirror_reflection(V, N) to node (0, 0); a pure Dirac (MIRROR_ONLY) has no other term.
// Twin: explorer.views.albedo.albedo_numpy (explorer.views.plots.plot_numpy).
#include "lib/views.glsl"

#define ALBEDO_MAX_NODES 256
uniform vec2 resolution;
uniform int albedo_nodes;
uniform float albedo_theta_h[ALBEDO_MAX_NODES];
uniform float albedo_d_theta[ALBEDO_MAX_NODES];
uniform int albedo_phi_nodes;
uniform int albedo_first_column;
uniform int albedo_columns;
out vec4 frag_colour;

void main() {
    int p = int(gl_FragCoord.x);
    int row = int(resolution.y - gl_FragCoord.y);  // from the top
    int k = row % albedo_nodes;
    int column = albedo_first_column + row / albedo_nodes;
    float theta_i = radians(90.0) * (float(column) + 0.5) / float(albedo_columns);
    vec3 normal = vec3(0.0, 0.0, 1.0);
    vec3 incident = vec3(sin(theta_i), 0.0, cos(theta_i));
    vec3 term = vec3(0.0);
#ifdef HAS_MIRROR_REFLECTION
    if (k == 0 && p == 0) term += finite_or_zero(mirror_reflection(incident, normal));
#endif
#ifndef MIRROR_ONLY
    float d_phi = radians(360.0) / float(albedo_phi_nodes);
    float theta_h = albedo_theta_h[k];
    float weight = 4.0 * sin(theta_h) * albedo_d_theta[k] * d_phi;
    vec3 h = unit_direction(theta_h, (float(p) + 0.5) * d_phi);
    float i_dot_h = dot(incident, h);
    vec3 o = 2.0 * i_dot_h * h - incident;
    if (i_dot_h > 0.0 && o.z > 0.0) {
        term += view_brdf(incident, o, normal, vec3(1.0, 0.0, 0.0), vec3(0.0, 1.0, 0.0)) * (o.z * weight * i_dot_h);
    }
#endif
    frag_colour = vec4(term, 1.0);
}
