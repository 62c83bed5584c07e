// Fresnel equations with Snell's law and total internal reflection: twin of explorer/physics/fresnel.py.
#include "lib/complex.glsl"

// Cosine of the refraction angle (complex: purely imaginary, Im > 0, under total internal reflection).
vec2 cos_theta_transmitted(float cos_theta_i, float eta_i, float eta_t) {
    float ratio = eta_i / eta_t;
    float cos2_theta_t = 1.0 - ratio * ratio * (1.0 - cos_theta_i * cos_theta_i);
    return cos2_theta_t >= 0.0 ? vec2(sqrt(cos2_theta_t), 0.0) : vec2(0.0, sqrt(-cos2_theta_t));
}

bool is_total_internal_reflection(float cos_theta_i, float eta_i, float eta_t) {
    float ratio = eta_i / eta_t;
    return ratio * ratio * (1.0 - cos_theta_i * cos_theta_i) > 1.0;
}

// Amplitude reflection coefficients, 's' (TE) and 'p' (TM, the tmm sign convention).
vec2 fresnel_r_s(float eta_i, vec2 cos_theta_i, float eta_t, vec2 cos_theta_t) {
    vec2 a = eta_i * cos_theta_i, b = eta_t * cos_theta_t;
    return cdiv(a - b, a + b);
}
vec2 fresnel_r_p(float eta_i, vec2 cos_theta_i, float eta_t, vec2 cos_theta_t) {
    vec2 a = eta_t * cos_theta_i, b = eta_i * cos_theta_t;
    return cdiv(a - b, a + b);
}
// polarisation: 0 = 's', 1 = 'p'
vec2 fresnel_r(int polarisation, float eta_i, vec2 cos_theta_i, float eta_t, vec2 cos_theta_t) {
    return polarisation == 0 ? fresnel_r_s(eta_i, cos_theta_i, eta_t, cos_theta_t)
                             : fresnel_r_p(eta_i, cos_theta_i, eta_t, cos_theta_t);
}

// Unpolarised reflectance of a smooth dielectric interface.
float fresnel_reflectance(float cos_theta_i, float eta_i, float eta_t) {
    vec2 cos_theta_t = cos_theta_transmitted(cos_theta_i, eta_i, eta_t);
    vec2 ci = vec2(cos_theta_i, 0.0);
    return 0.5 * (cabs2(fresnel_r_s(eta_i, ci, eta_t, cos_theta_t)) + cabs2(fresnel_r_p(eta_i, ci, eta_t, cos_theta_t)));
}

float fresnel_schlick(float cos_theta_i, float F0) {
    float m = 1.0 - cos_theta_i;
    return F0 + (1.0 - F0) * (m * m) * (m * m) * m;
}
