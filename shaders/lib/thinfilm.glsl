// Thin films: twin of the subpackage explorer/physics/thinfilm/, function for function and under the same names.
// Belcour, Barla (2017), A Practical Extension to Microfacet Theory for the Modeling of Varying
// Iridescence: Sections 3-5 and the Appendix. Equation numbers are the paper's.
//
// A film of real index eta_2 and thickness thickness_d (nm) lies on a base eta_3 + i kappa_3 under an
// exterior eta_1; cos_theta_1 is the cosine of the incidence angle in the exterior. Complex numbers are
// vec2 (lib/complex.glsl); polarisation 0 = 's', 1 = 'p'; wavelengths and OPDs in nm.
//
// float32 (the numpy twin runs in float64):
// - no acos/asin/atan: drivers (Mesa among them) lower them to low-precision polynomials. The phases on
//   reflection phi_21, phi_23 are carried as unit phasors e^{i phi} = r / |r| and their half angles, so
//   cos(m phi_2), sin(m phi_2) are powers of a phasor and sin(Phi / 2) is the imaginary part of a
//   product of half-angle phasors, never 1 - cos Phi;
// - R = 1 - T12 T23 / |1 - R_l e^{i Phi}|^2 (the Appendix's closed form without its cancellation at
//   grazing angles, see explorer/physics/thinfilm/airy.py), with |1 - R_l e^{i Phi}|^2 = (1 - R_l)^2 + 4 R_l sin^2(Phi/2)
//   and 1 - R_l = (T21 + T23 - T21 T23) / (1 + R_l); T12 = T21 = |t12 t21| and T23 from |t23|^2 (no 1 - R);
// - complex square roots without cancellation (csqrt); phases reduced to one turn (fract) before sin/cos.
#include "lib/fresnel.glsl"
#include "lib/colorimetry.glsl"

// The sensitivity_fourier table of luts/ (explorer/tables/luts.py), bound by the host (explorer/gpu/renderer.py): 4096 x 2
// texels, row 0 the real parts and row 1 the imaginary parts of the demodulated envelopes E_j(mu) at
// mu = 10 k nm; S^_j(mu) = E_j(mu) exp(-2 pi i mu / carrier_j). Read by texelFetch and interpolated here
// (hardware filtering weights have 8 bits on many GPUs).
uniform sampler2D sensitivity_fourier;

// explorer.physics.thinfilm.COS_THETA_MIN (renamed: lib/bragg.glsl has its own COS_THETA_MIN).
#include "generated/thinfilm.glsl"  // the constants shared with explorer/physics (generated at assembly)
// The paper's Gaussian fits of the XYZ sensitivities in Fourier space (Fig. 5(b-c)).
// sensitivity: 0 = 'table', 1 = 'gaussian' (the 'exact' transform is numpy's validation only).
const int SENSITIVITY_TABLE = 0;
const int SENSITIVITY_GAUSSIAN = 1;
// Eq. 10 is summed explicitly to m_max <= M_MAX_LIMIT, the rest in closed form (fourier_remainder), which
// needs the harmonic m_max + 1: the sample arrays hold SAMPLES = M_MAX_LIMIT + 2 entries.
const int M_MAX_LIMIT = 3;
const int SAMPLES = M_MAX_LIMIT + 2;

// ---- Complex helpers ----------------------------------------------------------------------------

// Principal square root (Re >= 0), without cancellation on either side of the real axis.
vec2 csqrt(vec2 z) {
    float r = length(z);
    if (z.x >= 0.0) {
        float t = sqrt(0.5 * (r + z.x));
        return t > 0.0 ? vec2(t, z.y / (2.0 * t)) : vec2(0.0);
    }
    float t = sqrt(0.5 * (r - z.x));
    return vec2(abs(z.y) / (2.0 * t), z.y < 0.0 ? -t : t);
}

// e^{i arg z} (np.angle(0) = 0: the phasor 1 for z = 0).
vec2 unit_phasor(vec2 z) {
    float r2 = cabs2(z);
    return r2 > 1e-36 ? z * inversesqrt(r2) : vec2(1.0, 0.0);
}

// One square root of a unit phasor e^{i a}: e^{i a / 2} up to a sign, from the stable half-angle
// formulas (sin^2 and products of such phasors do not depend on the sign).
vec2 half_phasor(vec2 u) {
    if (u.x >= 0.0) {
        float c = sqrt(0.5 * (1.0 + u.x));
        return vec2(c, u.y / (2.0 * c));
    }
    float s = sqrt(0.5 * (1.0 - u.x));
    return vec2(abs(u.y) / (2.0 * s), u.y < 0.0 ? -s : s);
}

// e^{i 2 pi x}, x reduced to one turn first.
vec2 exp_i_turns(float x) {
    float a = 2.0 * PI * fract(x);
    return vec2(cos(a), sin(a));
}

// ---- Snell and Fresnel with a conducting base (lib/fresnel.glsl is dielectric-only) --------------

// Cosine of the complex refraction angle into eta_3 + i kappa_3, through q_3 = n_3 cos theta_3 =
// sqrt(n_3^2 - eta_1^2 sin^2 theta_1) on the branch Im q_3 >= 0.
vec2 cos_theta_transmitted_conductor(float cos_theta_1, float eta_1, float eta_3, float kappa_3) {
    vec2 n_3 = vec2(eta_3, kappa_3);
    float sin2_theta_1 = (1.0 - cos_theta_1) * (1.0 + cos_theta_1);
    vec2 q_3 = csqrt(cmul(n_3, n_3) - vec2(eta_1 * eta_1 * sin2_theta_1, 0.0));
    if (q_3.y < 0.0) q_3 = -q_3;
    if (cabs2(q_3) < 1e-24) q_3 = vec2(0.0, 1e-12);  // exactly at a critical angle
    return cdiv(q_3, n_3);
}

// Amplitude reflection coefficient into a complex index eta_t (the tmm convention, as fresnel_r).
vec2 fresnel_r(int polarisation, float eta_i, vec2 cos_theta_i, vec2 eta_t, vec2 cos_theta_t) {
    vec2 a, b;
    if (polarisation == 0) { a = eta_i * cos_theta_i; b = cmul(eta_t, cos_theta_t); }
    else { a = cmul(eta_t, cos_theta_i); b = eta_i * cos_theta_t; }
    return cdiv(a - b, a + b);
}

// Amplitude transmission coefficient: t_s = 2 a / (a + b), t_p = 2 a / (eta_t cos_i + eta_i cos_t).
vec2 fresnel_t(int polarisation, float eta_i, vec2 cos_theta_i, vec2 eta_t, vec2 cos_theta_t) {
    vec2 a = eta_i * cos_theta_i;
    if (polarisation == 0) return cdiv(2.0 * a, a + cmul(eta_t, cos_theta_t));
    return cdiv(2.0 * a, cmul(eta_t, cos_theta_i) + eta_i * cos_theta_t);
}

// T / |t|^2 for a wave leaving the real medium eta_i into eta_t (numpy's _power_factor).
float power_factor(int polarisation, float eta_i, vec2 cos_theta_i, vec2 eta_t, vec2 cos_theta_t) {
    vec2 flux_t = polarisation == 0 ? cmul(eta_t, cos_theta_t) : cmul(eta_t, cconj(cos_theta_t));
    return flux_t.x / (eta_i * cos_theta_i.x);
}

// ---- The film at one angle and polarisation (Section 3, Eq. 6 and Appendix) ----------------------

struct FilmTerms {
    float cos_theta_1;
    vec2 cos_theta_2, cos_theta_3;
    float eta_1, eta_2;
    vec2 n_3;
    float thickness_d;
    vec2 r12, r21, r23, t12, t21, t23;
    int polarisation;
};

bool film_propagates(FilmTerms t) { return t.cos_theta_2.y == 0.0 && t.cos_theta_2.x > 0.0; }

// D = 2 eta_2 d cos theta_2 (Section 3).
float optical_path_difference(float eta_2, float cos_theta_2, float thickness_d) { return 2.0 * eta_2 * cos_theta_2 * thickness_d; }

// The OPD (0 where the film is evanescent).
float D(FilmTerms t) { return optical_path_difference(t.eta_2, film_propagates(t) ? t.cos_theta_2.x : 0.0, t.thickness_d); }

float R12(FilmTerms t) { return cabs2(t.r12); }
float R21(FilmTerms t) { return cabs2(t.r21); }
float R23(FilmTerms t) { return cabs2(t.r23); }
// |t12| |t21| = T12 = T21 = 1 - R12 where the film propagates, without cancellation.
float sqrt_T12T21(FilmTerms t) { return sqrt(cabs2(cmul(t.t12, t.t21))); }
// 1 - R23 (0 under total internal reflection; for a conductor, the power it absorbs), without cancellation.
float T23(FilmTerms t) { return power_factor(t.polarisation, t.eta_2, t.cos_theta_2, t.n_3, t.cos_theta_3) * cabs2(t.t23); }
float R_l(FilmTerms t) { return sqrt(R23(t) * R21(t)); }
// 1 - R23 R21 = T21 + T23 - T21 T23 where the film propagates.
float one_minus_R_l2(FilmTerms t) {
    float T21 = sqrt_T12T21(t), T_23 = T23(t);
    return T21 + T_23 - T21 * T_23;
}
// R* = T12 T21 R23 / (1 - R23 R21) (Eq. 6).
float R_star(FilmTerms t) { float T = sqrt_T12T21(t); return T * T * R23(t) / one_minus_R_l2(t); }
// e^{i phi_2}, phi_2 = phi_21 + phi_23 the phases of r21 and r23 (Eq. 9): numpy's phi_2 as a phasor.
vec2 exp_i_phi_2(FilmTerms t) { return cmul(unit_phasor(t.r21), unit_phasor(t.r23)); }
// e^{i phi_2 / 2} up to a sign.
vec2 exp_i_half_phi_2(FilmTerms t) { return cmul(half_phasor(unit_phasor(t.r21)), half_phasor(unit_phasor(t.r23))); }
// T12 T23 = (eta_3 cos theta_3)/(eta_1 cos theta_1) |t12|^2 |t23|^2 (Appendix).
float T12T23(FilmTerms t) {
    return power_factor(t.polarisation, t.eta_1, vec2(t.cos_theta_1, 0.0), t.n_3, t.cos_theta_3) * cabs2(cmul(t.t12, t.t23));
}

FilmTerms film_terms(float eta_1, float eta_2, float eta_3, float kappa_3, float cos_theta_1, float thickness_d, int polarisation) {
    FilmTerms t;
    t.cos_theta_1 = clamp(cos_theta_1, FILM_COS_THETA_MIN, 1.0);
    vec2 cos_1 = vec2(t.cos_theta_1, 0.0);
    t.cos_theta_2 = cos_theta_transmitted(t.cos_theta_1, eta_1, eta_2);
    if (cabs2(t.cos_theta_2) < 1e-24) t.cos_theta_2 = vec2(0.0, 1e-12);  // exactly at the film's critical angle
    t.cos_theta_3 = cos_theta_transmitted_conductor(t.cos_theta_1, eta_1, eta_3, kappa_3);
    t.eta_1 = eta_1;
    t.eta_2 = eta_2;
    t.n_3 = vec2(eta_3, kappa_3);
    t.thickness_d = thickness_d;
    t.r12 = fresnel_r(polarisation, eta_1, cos_1, eta_2, t.cos_theta_2);
    t.r21 = fresnel_r(polarisation, eta_2, t.cos_theta_2, eta_1, cos_1);
    t.r23 = fresnel_r(polarisation, eta_2, t.cos_theta_2, t.n_3, t.cos_theta_3);
    t.t12 = fresnel_t(polarisation, eta_1, cos_1, vec2(eta_2, 0.0), t.cos_theta_2);
    t.t21 = fresnel_t(polarisation, eta_2, t.cos_theta_2, vec2(eta_1, 0.0), cos_1);
    t.t23 = fresnel_t(polarisation, eta_2, t.cos_theta_2, t.n_3, t.cos_theta_3);
    t.polarisation = polarisation;
    return t;
}

// ---- Airy reflectance (Eqs. 2-3, Appendix) -------------------------------------------------------

// exp(i Delta phi) with the complex Delta phi = 2 pi 2 eta_2 d cos theta_2 / lambda (decays where evanescent).
vec2 complex_phase(FilmTerms t, float wavelength) {
    return cexpi(2.0 * PI * 2.0 * t.eta_2 * t.thickness_d * t.cos_theta_2 / wavelength);
}

// Eq. 3: r = r12 + t12 r23 t21 e^{i Dphi} / (1 - r21 r23 e^{i Dphi}).
vec2 airy_reflection_coefficient_from_terms(FilmTerms t, float wavelength) {
    vec2 e = complex_phase(t, wavelength);
    return t.r12 + cdiv(cmul(cmul(t.t12, t.r23), cmul(t.t21, e)), vec2(1.0, 0.0) - cmul(cmul(t.r21, t.r23), e));
}

// The closed form's wavelength-independent factors: R = 1 - numerator / ((1 - R_l)^2 + 4 R_l sin^2(Phi/2)).
struct AiryClosedForm {
    float numerator, one_minus_R_l, R_l;
    vec2 half_phase_2;  // e^{i phi_2 / 2}
};

AiryClosedForm airy_closed_form(FilmTerms t) {
    AiryClosedForm a;
    a.R_l = R_l(t);
    a.numerator = sqrt_T12T21(t) * T23(t);
    a.one_minus_R_l = one_minus_R_l2(t) / (1.0 + a.R_l);
    a.half_phase_2 = exp_i_half_phi_2(t);
    return a;
}

// e^{i Delta phi / 2} = e^{i pi D / lambda}: shared by both polarisations (D does not depend on it).
vec2 half_delta_phase(float D_, float wavelength) { return exp_i_turns(0.5 * D_ / wavelength); }

// |1 - R_l e^{i Phi}|^2 = (1 - R_l)^2 + 4 R_l sin^2(Phi / 2), Phi = Delta phi + phi_2.
float airy_denominator(AiryClosedForm a, vec2 half_delta) {
    float s = half_delta.x * a.half_phase_2.y + half_delta.y * a.half_phase_2.x;  // sin(Phi / 2) up to a sign
    return a.one_minus_R_l * a.one_minus_R_l + 4.0 * a.R_l * s * s;
}

float airy_reflectance_closed(AiryClosedForm a, vec2 half_delta) { return 1.0 - a.numerator / airy_denominator(a, half_delta); }

// One polarisation: the closed form where the film propagates, |r|^2 of Eq. 3 where it is evanescent.
float airy_reflectance_from_terms(FilmTerms t, float wavelength) {
    if (film_propagates(t)) return airy_reflectance_closed(airy_closed_form(t), half_delta_phase(D(t), wavelength));
    return cabs2(airy_reflection_coefficient_from_terms(t, wavelength));
}

// Unpolarised R = (|r_s|^2 + |r_p|^2) / 2 at one wavelength.
float airy_reflectance(float eta_1, float eta_2, float eta_3, float kappa_3, float cos_theta_1, float thickness_d, float wavelength) {
    return 0.5 * (airy_reflectance_from_terms(film_terms(eta_1, eta_2, eta_3, kappa_3, cos_theta_1, thickness_d, 0), wavelength) +
                  airy_reflectance_from_terms(film_terms(eta_1, eta_2, eta_3, kappa_3, cos_theta_1, thickness_d, 1), wavelength));
}

// ---- The Fourier series of R (Eqs. 5-6) ----------------------------------------------------------

// C_0 = R12 + R* (Eq. 6).
float C_0(FilmTerms t) { return R12(t) + R_star(t); }

// C_m = (sqrt(R23 R21))^m (R* - sqrt(T12 T21)) (Eq. 6), as -R_l^m T12 T23 / (1 - R_l^2) (no cancellation).
float C_m(FilmTerms t, int m) {
    float R = R_l(t), power = 1.0;
    for (int k = 0; k < m; ++k) power *= R;
    return -power * sqrt_T12T21(t) * T23(t) / one_minus_R_l2(t);
}

// ---- The sensitivities in Fourier space (Eqs. 7-8, Section 5) ------------------------------------

// The demodulated envelope E_j(mu) of the table, interpolated linearly between nodes (as numpy does);
// false beyond the last node, where S^ is taken as 0.
bool sensitivity_fourier_envelope(float mu, out vec3 re, out vec3 im) {
    int last = textureSize(sensitivity_fourier, 0).x - 1;
    float x = mu / SENSITIVITY_FOURIER_STEP;
    re = vec3(0.0);
    im = vec3(0.0);
    if (!(x >= 0.0 && x <= float(last))) return false;
    int i = min(int(floor(x)), last - 1);
    float f = x - float(i);
    re = mix(texelFetch(sensitivity_fourier, ivec2(i, 0), 0).rgb, texelFetch(sensitivity_fourier, ivec2(i + 1, 0), 0).rgb, f);
    im = mix(texelFetch(sensitivity_fourier, ivec2(i, 1), 0).rgb, texelFetch(sensitivity_fourier, ivec2(i + 1, 1), 0).rgb, f);
    return true;
}

// The carriers exp(-2 pi i mu / carrier_j) (real parts in c, imaginary in s), reduced to one turn.
void sensitivity_fourier_carrier(float mu, out vec3 c, out vec3 s) {
    vec3 a = 2.0 * PI * fract(mu / SENSITIVITY_FOURIER_CARRIER_NM);
    c = cos(a);
    s = -sin(a);
}

// S^_j(mu) from the table: the envelope times the carrier; 0 beyond the last node.
void sensitivity_fourier_transform_table(float mu, out vec3 re, out vec3 im) {
    vec3 env_re, env_im, c, s;
    if (!sensitivity_fourier_envelope(mu, env_re, env_im)) { re = vec3(0.0); im = vec3(0.0); return; }
    sensitivity_fourier_carrier(mu, c, s);
    re = env_re * c - env_im * s;
    im = env_re * s + env_im * c;
}

// The paper's Gaussian fits in XYZ: sum val sqrt(2 pi var) exp(-var phase^2) exp(-i pos phase) / norm,
// phase = 2 pi mu 1e-9 (mu in nm, the fits in metres).
void sensitivity_fourier_transform_gaussian_xyz(float mu, out vec3 re, out vec3 im) {
    float phase = 2.0 * PI * 1e-9 * mu;
    vec3 amplitude = GAUSSIAN_FIT_VAL * sqrt(2.0 * PI * GAUSSIAN_FIT_VAR) * exp(-GAUSSIAN_FIT_VAR * phase * phase) / GAUSSIAN_FIT_NORM;
    vec3 turns = fract(GAUSSIAN_FIT_POS * (1e-9 * mu));  // pos phase / (2 pi), reduced
    re = amplitude * cos(2.0 * PI * turns);
    im = -amplitude * sin(2.0 * PI * turns);
    float amplitude_2 = GAUSSIAN_FIT_X2.x * sqrt(2.0 * PI * GAUSSIAN_FIT_X2.z) * exp(-GAUSSIAN_FIT_X2.z * phase * phase) / GAUSSIAN_FIT_NORM;
    float turns_2 = 2.0 * PI * fract(GAUSSIAN_FIT_X2.y * (1e-9 * mu));
    re.x += amplitude_2 * cos(turns_2);
    im.x -= amplitude_2 * sin(turns_2);
}

// S^_j(mu) of the linear sRGB sensitivities (Eq. 8): the table, or the Gaussian fits taken to RGB.
void sensitivity_fourier_transform(float mu, int sensitivity, out vec3 re, out vec3 im) {
    if (sensitivity == SENSITIVITY_TABLE) {
        sensitivity_fourier_transform_table(mu, re, im);
        return;
    }
    sensitivity_fourier_transform_gaussian_xyz(mu, re, im);
    re = xyz_to_rgb(re);
    im = xyz_to_rgb(im);
}

// ---- Analytic spectral integration (Eq. 10) ------------------------------------------------------

// S^(m D) for m = 0..m_max: they depend on the film's OPD only, so both polarisations share them. For
// the table, S^(0) = 1 and the carriers of m D are the m-th powers of those of D: four texel fetches and
// no trig per harmonic.
// The pre-filtered table (explorer.physics.thinfilm.sensitivity_fourier_prefiltered), bound by the host on first
// use: 4096 x (2 x PREFILTER_LEVELS) texels, rows k = 0..127 the real parts and rows 128 + k the imaginary
// parts of the envelope convolved with a Gaussian of standard deviation k PREFILTER_SIGMA_STEP nm.
uniform sampler2D sensitivity_fourier_prefiltered;

// The envelope at OPD mean mu and standard deviation sigma, bilinear in (mu, sigma) by texelFetch as numpy
// does; false beyond the last mu node; sigma clamped to the last level.
bool sensitivity_fourier_envelope_prefiltered(float mu, float sigma, out vec3 re, out vec3 im) {
    int last = textureSize(sensitivity_fourier_prefiltered, 0).x - 1;
    float x = mu / SENSITIVITY_FOURIER_STEP;
    re = vec3(0.0);
    im = vec3(0.0);
    if (!(x >= 0.0 && x <= float(last))) return false;
    int i = min(int(floor(x)), last - 1);
    float f = x - float(i);
    float y = clamp(sigma / PREFILTER_SIGMA_STEP, 0.0, float(PREFILTER_LEVELS - 1));
    int k = min(int(floor(y)), PREFILTER_LEVELS - 2);
    float g = y - float(k);
    for (int part = 0; part < 2; ++part) {
        int row = k + part * PREFILTER_LEVELS;
        vec3 low = mix(texelFetch(sensitivity_fourier_prefiltered, ivec2(i, row), 0).rgb, texelFetch(sensitivity_fourier_prefiltered, ivec2(i + 1, row), 0).rgb, f);
        vec3 high = mix(texelFetch(sensitivity_fourier_prefiltered, ivec2(i, row + 1), 0).rgb, texelFetch(sensitivity_fourier_prefiltered, ivec2(i + 1, row + 1), 0).rgb, f);
        if (part == 0) re = mix(low, high, g); else im = mix(low, high, g);
    }
    return true;
}

// Table-based S^(m D) for m = 0..m_max: the carrier exp(+2 pi i m D / carrier) by powers times the
// demodulated envelope, read from the prefiltered table at standard deviation m sigma_D when sigma_D >= 0
// (Section 5), from sensitivity_fourier otherwise.
void sensitivity_samples_table(float D_, float sigma_D, int m_max, out vec3 re[SAMPLES], out vec3 im[SAMPLES]) {
    for (int m = 0; m < SAMPLES; ++m) { re[m] = vec3(0.0); im[m] = vec3(0.0); }
    re[0] = vec3(1.0);  // S^(0) = E(0) = sum_lambda s_j(lambda) = 1 (white): the table's node 0, exactly
    vec3 c, s, power_c = vec3(1.0), power_s = vec3(0.0);
    sensitivity_fourier_carrier(D_, c, s);
    for (int m = 1; m < SAMPLES; ++m) {
        if (m > m_max + 1) break;
        vec3 next_c = power_c * c - power_s * s;
        power_s = power_c * s + power_s * c;
        power_c = next_c;
        vec3 env_re, env_im;
        bool inside = sigma_D >= 0.0 ? sensitivity_fourier_envelope_prefiltered(float(m) * D_, float(m) * sigma_D, env_re, env_im)
                                     : sensitivity_fourier_envelope(float(m) * D_, env_re, env_im);
        if (!inside) break;  // and beyond for larger m
        re[m] = env_re * power_c - env_im * power_s;
        im[m] = env_re * power_s + env_im * power_c;
    }
}

void sensitivity_samples(float D_, int m_max, int sensitivity, out vec3 re[SAMPLES], out vec3 im[SAMPLES]) {
    if (sensitivity == SENSITIVITY_TABLE) {
        sensitivity_samples_table(D_, -1.0, m_max, re, im);
        return;
    }
    for (int m = 0; m < SAMPLES; ++m) {
        re[m] = vec3(0.0); im[m] = vec3(0.0);
        if (m <= m_max + 1) sensitivity_fourier_transform(float(m) * D_, sensitivity, re[m], im[m]);
    }
}

// The terms of Eq. 10 beyond m_max in closed form (explorer.physics.thinfilm.fourier_remainder): with
// z_m = e^{-i m phi_2} S^(m D) extrapolated geometrically, z_m ~ z_M r^(m - M), r = z_(M+1) / z_M
// (|r| <= 1), and C_m = C_M R_l^(m - M), they sum to 2 C_M Re(z_M q / (1 - q)), q = R_l r. Exact as
// D -> 0; it keeps the series under 1 near total internal reflection in the film, where R_l -> 1.
vec3 fourier_remainder(float R, float two_C_M, vec3 z_re, vec3 z_im, vec3 next_re, vec3 next_im) {
    vec3 rgb;
    for (int j = 0; j < 3; ++j) {
        vec2 z = vec2(z_re[j], z_im[j]), next = vec2(next_re[j], next_im[j]);
        float power = dot(z, z);  // |z| > REMAINDER_MIN, else the remainder is negligible
        vec2 r = power > REMAINDER_MIN * REMAINDER_MIN ? cmul(next, vec2(z.x, -z.y)) / power : vec2(0.0);
        r /= max(length(r), 1.0);
        vec2 q = R * r, one_minus_q = vec2(1.0 - q.x, -q.y);
        vec2 zq = cmul(z, q);
        rgb[j] = two_C_M * dot(zq, one_minus_q) / dot(one_minus_q, one_minus_q);  // Re(zq / (1 - q))
    }
    return rgb;
}

// Eq. 10 for one polarisation from the samples S^(m D): R_j = C_0 Re S^_j(0) + 2 sum_m C_m [cos(m phi_2)
// Re S^_j(m D) + sin(m phi_2) Im S^_j(m D)], e^{i m phi_2} by powers of the phasor, plus the remainder.
vec3 spectral_integration_fourier_samples(FilmTerms t, int m_max, vec3 re[SAMPLES], vec3 im[SAMPLES]) {
    vec3 rgb = C_0(t) * re[0];
    float R = R_l(t), factor = -2.0 * sqrt_T12T21(t) * T23(t) / one_minus_R_l2(t);  // 2 C_m = factor R_l^m
    vec2 phase = exp_i_phi_2(t), phase_m = vec2(1.0, 0.0);
    vec3 z_re = re[0], z_im = im[0];  // z_m = conj(e^{i m phi_2}) S^(m D)
    for (int m = 1; m <= M_MAX_LIMIT; ++m) {
        if (m > m_max) break;
        factor *= R;
        phase_m = cmul(phase_m, phase);
        z_re = phase_m.x * re[m] + phase_m.y * im[m];
        z_im = phase_m.x * im[m] - phase_m.y * re[m];
        rgb += factor * z_re;
    }
    int next = min(m_max + 1, SAMPLES - 1);
    phase_m = cmul(phase_m, phase);
    vec3 next_re = phase_m.x * re[next] + phase_m.y * im[next], next_im = phase_m.x * im[next] - phase_m.y * re[next];
    return rgb + fourier_remainder(R, factor, z_re, z_im, next_re, next_im);
}

vec3 spectral_integration_fourier(FilmTerms t, int m_max, int sensitivity) {
    vec3 re[SAMPLES], im[SAMPLES];
    sensitivity_samples(D(t), m_max, sensitivity, re, im);
    return spectral_integration_fourier_samples(t, m_max, re, im);
}

// ---- Colours: spectral reference, Fourier method, naive method -----------------------------------

// The spectral reference: the Airy reflectance at every nm from 360 to 830, both polarisations, against the CMFs.
vec3 reference_rgb(float eta_1, float eta_2, float eta_3, float kappa_3, float cos_theta_1, float thickness_d) {
    FilmTerms s = film_terms(eta_1, eta_2, eta_3, kappa_3, cos_theta_1, thickness_d, 0);
    FilmTerms p = film_terms(eta_1, eta_2, eta_3, kappa_3, cos_theta_1, thickness_d, 1);
    vec3 xyz = vec3(0.0);
    if (film_propagates(s)) {
        AiryClosedForm a_s = airy_closed_form(s), a_p = airy_closed_form(p);
        float D_ = D(s);
        for (int i = 0; i < CMF_COUNT; ++i) {
            vec2 half_delta = half_delta_phase(D_, CMF_FIRST_WAVELENGTH + float(i));
            float R = 0.5 * (airy_reflectance_closed(a_s, half_delta) + airy_reflectance_closed(a_p, half_delta));
            xyz += R * colour_matching_functions(i);
        }
    } else {
        for (int i = 0; i < CMF_COUNT; ++i) {
            float wavelength = CMF_FIRST_WAVELENGTH + float(i);
            float R = 0.5 * (cabs2(airy_reflection_coefficient_from_terms(s, wavelength)) +
                             cabs2(airy_reflection_coefficient_from_terms(p, wavelength)));
            xyz += R * colour_matching_functions(i);
        }
    }
    return xyz_to_rgb(xyz);
}

// The naive RGB method: the Airy reflectance at one wavelength per channel (Section 4).
vec3 naive_rgb(float eta_1, float eta_2, float eta_3, float kappa_3, float cos_theta_1, float thickness_d) {
    FilmTerms s = film_terms(eta_1, eta_2, eta_3, kappa_3, cos_theta_1, thickness_d, 0);
    FilmTerms p = film_terms(eta_1, eta_2, eta_3, kappa_3, cos_theta_1, thickness_d, 1);
    vec3 rgb;
    if (film_propagates(s)) {  // the closed form's factors once per polarisation
        AiryClosedForm a_s = airy_closed_form(s), a_p = airy_closed_form(p);
        float D_ = D(s);
        for (int j = 0; j < 3; ++j) {
            vec2 half_delta = half_delta_phase(D_, NAIVE_WAVELENGTHS[j]);
            rgb[j] = 0.5 * (airy_reflectance_closed(a_s, half_delta) + airy_reflectance_closed(a_p, half_delta));
        }
        return rgb;
    }
    for (int j = 0; j < 3; ++j)
        rgb[j] = 0.5 * (airy_reflectance_from_terms(s, NAIVE_WAVELENGTHS[j]) + airy_reflectance_from_terms(p, NAIVE_WAVELENGTHS[j]));
    return rgb;
}

// Eq. 10 truncated at m_max (1 to 3), both polarisations; the naive colour where the film is evanescent.
vec3 fourier_rgb(float eta_1, float eta_2, float eta_3, float kappa_3, float cos_theta_1, float thickness_d, int m_max, int sensitivity) {
    FilmTerms s = film_terms(eta_1, eta_2, eta_3, kappa_3, cos_theta_1, thickness_d, 0);
    FilmTerms p = film_terms(eta_1, eta_2, eta_3, kappa_3, cos_theta_1, thickness_d, 1);
    if (!film_propagates(s)) {  // naive_rgb's evanescent branch, from the same terms
        vec3 rgb;
        for (int j = 0; j < 3; ++j)
            rgb[j] = 0.5 * (cabs2(airy_reflection_coefficient_from_terms(s, NAIVE_WAVELENGTHS[j])) +
                            cabs2(airy_reflection_coefficient_from_terms(p, NAIVE_WAVELENGTHS[j])));
        return rgb;
    }
    vec3 re[SAMPLES], im[SAMPLES];
    sensitivity_samples(D(s), m_max, sensitivity, re, im);
    return 0.5 * (spectral_integration_fourier_samples(s, m_max, re, im) + spectral_integration_fourier_samples(p, m_max, re, im));
}

// ---- Parametrisation by the OPD at normal incidence (Section 5) ----------------------------------


// D_inc = 2 eta_2 d.
float D_inc(float eta_2, float thickness_d) { return 2.0 * eta_2 * thickness_d; }

// The film (eta_2', d) an artist's D_inc stands for: eta_2 -> eta_1 as D_inc -> 0 (smoothstep over 30 nm).
void film_from_D_inc(float D_inc_, float eta_1, float eta_2, out float eta_2_effective, out float thickness_d) {
    float t = clamp(D_inc_ / D_INC_BLEND, 0.0, 1.0);
    eta_2_effective = eta_1 + (eta_2 - eta_1) * (t * t * (3.0 - 2.0 * t));
    thickness_d = D_inc_ / (2.0 * eta_2_effective);
}

// ---- Multi-scale rendering: Eq. 10 averaged over a Gaussian distribution of OPD (Section 5) ------

// Eq. 10 against a Gaussian distribution of thickness: each harmonic's S^(m D) is replaced by its
// average over OPDs of mean m D and standard deviation m cos(theta_2) sigma_D_inc (D = D_inc cos theta_2).
// thickness_d is the mean thickness; the naive colour where the film is evanescent, as fourier_rgb.
vec3 fourier_rgb_prefiltered(float eta_1, float eta_2, float eta_3, float kappa_3, float cos_theta_1, float thickness_d, float sigma_D_inc, int m_max) {
    FilmTerms s = film_terms(eta_1, eta_2, eta_3, kappa_3, cos_theta_1, thickness_d, 0);
    FilmTerms p = film_terms(eta_1, eta_2, eta_3, kappa_3, cos_theta_1, thickness_d, 1);
    if (!film_propagates(s)) {
        vec3 rgb;
        for (int j = 0; j < 3; ++j)
            rgb[j] = 0.5 * (cabs2(airy_reflection_coefficient_from_terms(s, NAIVE_WAVELENGTHS[j])) +
                            cabs2(airy_reflection_coefficient_from_terms(p, NAIVE_WAVELENGTHS[j])));
        return rgb;
    }
    float D_ = D(s), sigma_D = sigma_D_inc * s.cos_theta_2.x;
    vec3 re[SAMPLES], im[SAMPLES];
    sensitivity_samples_table(D_, sigma_D, m_max, re, im);
    return 0.5 * (spectral_integration_fourier_samples(s, m_max, re, im) + spectral_integration_fourier_samples(p, m_max, re, im));
}
