// GGX microfacets: twin of explorer/physics/microfacet.py (Fourneau et al. 2024, Eqs. 17-19; Walter et al. 2007).
// Directions point away from the surface; the normal is N (n = +z in the numpy twin).
#include "lib/complex.glsl"

#include "generated/microfacet.glsl"  // the constants shared with explorer/physics (generated at assembly)

// Eq. 18: alpha^2 / (pi (alpha^2 cos^2 + sin^2)^2), with sin^2 = (1 - c)(1 + c): exact at m = n.
float ggx_D(float cos_theta_m, float alpha) {
    if (cos_theta_m <= 0.0) return 0.0;
    float a2 = max(alpha, ALPHA_MIN) * max(alpha, ALPHA_MIN), c = min(cos_theta_m, 1.0);
    float denominator = a2 * c * c + (1.0 - c) * (1.0 + c);
    return a2 / (PI * denominator * denominator);
}

// Eq. 19: 2 cos / (cos + sqrt(cos^2 + alpha^2 sin^2)), 0 at and below the horizon.
float smith_G1(float cos_theta_i, float alpha) {
    if (cos_theta_i <= 0.0) return 0.0;
    float a = max(alpha, ALPHA_MIN), c = min(cos_theta_i, 1.0);
    return 2.0 * c / (c + sqrt(c * c + a * a * (1.0 - c * c)));
}

// G1 / cos, finite at grazing incidence where both vanish.
float smith_G1_over_cos(float cos_theta_i, float alpha) {
    if (cos_theta_i <= 0.0) return 0.0;
    float a = max(alpha, ALPHA_MIN), c = min(cos_theta_i, 1.0);
    return 2.0 / (c + sqrt(c * c + a * a * (1.0 - c * c)));
}

// h = (i + o) / |i + o|; +N where i = -o.
vec3 half_vector(vec3 i, vec3 o, vec3 N) {
    vec3 s = i + o;
    float norm = length(s);
    return norm > 1e-12 ? s / norm : N;
}

// cos theta_d = |i + o| / 2: symmetric in i and o, so Eq. 17 stays exactly reciprocal.
float half_vector_cosine(vec3 i, vec3 o) { return clamp(0.5 * length(i + o), 0.0, 1.0); }

// Eq. 17 without its reflectance: D(h) G1(i) G1(o) / (4 |i.n| |o.n|); 0 unless both are above the surface.
// A material multiplies it by its microfacet reflectance at half_vector_cosine(i, o).
float microfacet_lobe(vec3 i, vec3 o, vec3 N, float alpha) {
    float cos_i = dot(i, N), cos_o = dot(o, N);
    if (cos_i <= 0.0 || cos_o <= 0.0) return 0.0;
    vec3 h = half_vector(i, o, N);
    return 0.25 * ggx_D(dot(h, N), alpha) * smith_G1_over_cos(cos_i, alpha) * smith_G1_over_cos(cos_o, alpha);
}
