// Bragg mirrors: twin of the subpackage explorer/physics/bragg/, function for function and under the same names.
// Fourneau, Pacanowski, Barla (2024), Interactive Exploration of Vivid Material Iridescence using
// Bragg Mirrors: Sections 3.1-3.2, Appendices A, B, D. Equation numbers are the paper's.
//
// A mirror is N cells of (n2, d2) then (n1, d1) under a host nh (nh < 1 means "the host is n1").
// omega = 2 pi / lambda in rad/nm; angles are cosines in the host.
#include "lib/fresnel.glsl"
#include "lib/colorimetry.glsl"

#include "generated/bragg.glsl"  // the constants shared with explorer/physics (generated at assembly)
const int CHEBYSHEV_BITS = 10;  // binary powering up to N = 1023

struct BraggMirror {
    float n1, n2, Lambda, delta, N, nh;
};

float eta_h(BraggMirror mirror) { return mirror.nh < 1.0 ? mirror.n1 : mirror.nh; }

// What a cell looks like at one angle and polarisation: p1 = n1 cos(theta_1) d1, p2 = n2 cos(theta_2) d2.
struct CellGeometry {
    vec2 cos_theta_1, cos_theta_2, p1, p2, r12, Omega, r_h1;
    float correction, N;
    bool host_is_n1;
};

float angular_correction(vec2 cos_theta_1, float n1, float n2);

// Eqs. 6-7 (polarisation 0 = 's', 1 = 'p').
vec2 Omega(int polarisation, float n1, vec2 cos_theta_1, float n2, vec2 cos_theta_2) {
    vec2 x = polarisation == 0 ? cdiv(n2 * cos_theta_2, n1 * cos_theta_1) : cdiv(n1 * cos_theta_2, n2 * cos_theta_1);
    if (cabs2(x) < 1e-20) x = vec2(1e-10, 0.0);  // exactly at a critical angle
    return x + cinv(x);
}

CellGeometry cell_geometry(float cos_theta_h, BraggMirror mirror, int polarisation) {
    cos_theta_h = max(cos_theta_h, COS_THETA_MIN);
    float host = eta_h(mirror);
    float d1 = mirror.delta * mirror.Lambda, d2 = (1.0 - mirror.delta) * mirror.Lambda;
    CellGeometry g;
    g.cos_theta_1 = cos_theta_transmitted(cos_theta_h, host, mirror.n1);
    g.cos_theta_2 = cos_theta_transmitted(cos_theta_h, host, mirror.n2);
    g.p1 = mirror.n1 * d1 * g.cos_theta_1;
    g.p2 = mirror.n2 * d2 * g.cos_theta_2;
    g.r12 = fresnel_r(polarisation, mirror.n1, g.cos_theta_1, mirror.n2, g.cos_theta_2);
    g.Omega = Omega(polarisation, mirror.n1, g.cos_theta_1, mirror.n2, g.cos_theta_2);
    g.r_h1 = fresnel_r(polarisation, host, vec2(cos_theta_h, 0.0), mirror.n1, g.cos_theta_1);
    g.correction = angular_correction(g.cos_theta_1, mirror.n1, mirror.n2);
    g.N = mirror.N;
    g.host_is_n1 = host == mirror.n1;
    return g;
}

// ---- Yeh's reflectance (Section 3.1) ---------------------------------------------------------------

// Eq. 10: the Airy slab's r1 = r12 (1 - e^{2i phi}) / (1 - r12^2 e^{2i phi}), t1 = (1 - r12^2) e^{i phi} / (...).
void airy_slab_coefficients(float omega, CellGeometry g, out vec2 r1, out vec2 t1) {
    vec2 phase = cexpi(omega * g.p2);
    vec2 phase2 = cmul(phase, phase);
    vec2 r12_2 = cmul(g.r12, g.r12);
    vec2 denominator = vec2(1.0, 0.0) - cmul(r12_2, phase2);
    r1 = cdiv(cmul(g.r12, vec2(1.0, 0.0) - phase2), denominator);
    t1 = cdiv(cmul(vec2(1.0, 0.0) - r12_2, phase), denominator);
}

float C_squared(vec2 r1, vec2 t1) { return cabs2(r1) / cabs2(t1); }

vec2 clamp_decay(vec2 phase) { return vec2(phase.x, min(phase.y, MAX_DECAY)); }

// Eq. 8, real also when a layer is evanescent.
float cos_K_Lambda(float omega, CellGeometry g) {
    if (g.p1.y == 0.0 && g.p2.y == 0.0) {
        // Every wave propagates: Omega and both phases are real.
        float psi = omega * g.p1.x, phi = omega * g.p2.x;
        return cos(psi) * cos(phi) - 0.5 * g.Omega.x * sin(psi) * sin(phi);
    }
    vec2 psi = clamp_decay(omega * g.p1), phi = clamp_decay(omega * g.p2);
    vec2 value = cmul(ccos(psi), ccos(phi)) - 0.5 * cmul(g.Omega, cmul(csin(psi), csin(phi)));
    return value.x;
}

// 1 - exp(-2x) without cancellation for small x.
float one_minus_exp_minus_2x(float x) {
    return x < 0.05 ? 2.0 * x * (1.0 - x + x * x * (2.0 / 3.0 - x / 3.0)) : 1.0 - exp(-2.0 * x);
}

float acosh_stable(float a) { return a > 1e4 ? log(2.0 * a) : log(a + sqrt((a - 1.0) * (a + 1.0))); }

// U_{N-1}, U_{N-2} of cos K Lambda, divided by U_{N-1} in band gaps (Eq. 9) where they overflow.
// d = 1 - |a| when known without cancellation (chebyshev_U_half_angles), else computed from a.
void chebyshev_U_d(float a, float d, float N, out float U_N1, out float U_N2, out float scale) {
    if (d > 0.0) {
        // e^{i N t} = (cos t + i sin t)^N by binary powering, never t itself: drivers lower acos to
        // low-precision polynomials, whose error sin(N t) would multiply by N.
        a = a >= 0.0 ? 1.0 - d : d - 1.0;
        float sin_t = sqrt(d * (2.0 - d));
        // A constant trip count (N <= 1000 < 2^10), which compilers unroll: llvmpipe ends a shader's
        // loops after 65535 iterations in all, and a fine-step spectral reference needs every one of them.
        vec2 z = vec2(a, sin_t), power = vec2(1.0, 0.0);
        int n = int(N);
        for (int bit = 0; bit < CHEBYSHEV_BITS; ++bit) {
            if ((n >> bit) == 0) continue;
            if (((n >> bit) & 1) != 0) power = cmul(power, z);
            z = cmul(z, z);
        }
        U_N1 = power.y / sin_t;                                    // sin(N t) / sin t
        U_N2 = (power.y * a - power.x * sin_t) / sin_t;            // sin((N - 1) t) / sin t
        scale = 1.0;
    } else {
        float x = max(acosh_stable(1.0 - d), 1e-12);
        float h_N = one_minus_exp_minus_2x(N * x);
        U_N1 = 1.0;
        U_N2 = sign(a) * exp(-x) * one_minus_exp_minus_2x((N - 1.0) * x) / h_N;
        scale = exp(-(N - 1.0) * x) * one_minus_exp_minus_2x(x) / h_N;
    }
}

void chebyshev_U(float a, float N, out float U_N1, out float U_N2, out float scale) {
    chebyshev_U_d(a, 1.0 - abs(a), N, U_N1, U_N2, scale);
}

// float32 near band edges, real phases: with h+- = (psi +- phi)/2 and Theta = 1/2 + Omega/4, Eq. 36 gives
// 1 - cos K Lambda = 2 (1 - Theta) sin^2 h- + 2 Theta sin^2 h+ and 1 + cos K Lambda = the same with cos^2:
// no cancellation against 1, so sin K Lambda keeps its relative precision where sin(N K Lambda) / sin K Lambda
// would amplify an absolute error of cos K Lambda. Four trig calls in all; sin phi = sin(h+ - h-) comes free.
// float64 (explorer/physics/bragg/reflectance.py) needs none of this.
void chebyshev_U_half_angles(vec4 half_angles, float Omega_, float N, out float U_N1, out float U_N2, out float scale) {
    float sm = half_angles.x, cm = half_angles.y, sp = half_angles.z, cp = half_angles.w;
    float Theta = 0.5 + 0.25 * Omega_;
    float one_minus_a = 2.0 * ((1.0 - Theta) * sm * sm + Theta * sp * sp);
    float one_plus_a = 2.0 * ((1.0 - Theta) * cm * cm + Theta * cp * cp);
    float a = one_minus_a <= one_plus_a ? 1.0 - one_minus_a : one_plus_a - 1.0;
    chebyshev_U_d(a, a >= 0.0 ? one_minus_a : one_plus_a, N, U_N1, U_N2, scale);
}

// (sin h-, cos h-, sin h+, cos h+): the same for both polarisations.
vec4 half_angles(float psi, float phi) {
    float h_minus = 0.5 * (psi - phi), h_plus = 0.5 * (psi + phi);
    return vec4(sin(h_minus), cos(h_minus), sin(h_plus), cos(h_plus));
}

float sin_phi_of(vec4 h) { return h.z * h.y - h.w * h.x; }  // sin(h+ - h-)

// Eqs. 2 and 9: |r1|^2 U^2 / (|r1|^2 U^2 + |t1|^2 scale^2).
float reflectance_yeh(vec2 r1, vec2 t1, float a, float N) {
    float U_N1, U_N2, scale;
    chebyshev_U(a, N, U_N1, U_N2, scale);
    float numerator = cabs2(r1) * U_N1 * U_N1;
    return numerator / (numerator + cabs2(t1) * scale * scale);
}

// chebyshev_U for a cell at omega: without cancellation near band edges when both phases are real.
void chebyshev_U_cell(float omega, CellGeometry g, float a, out float U_N1, out float U_N2, out float scale) {
    if (g.p1.y == 0.0 && g.p2.y == 0.0) chebyshev_U_half_angles(half_angles(omega * g.p1.x, omega * g.p2.x), g.Omega.x, g.N, U_N1, U_N2, scale);
    else chebyshev_U(a, g.N, U_N1, U_N2, scale);
}

// Appendix D: r_N = r1 U_{N-1} / (U_{N-1} - U_{N-2} t1 e^{i k1z d1}).
vec2 reflection_coefficient_bragg(vec2 r1, vec2 t1, float omega, CellGeometry g, float a) {
    float U_N1, U_N2, scale;
    chebyshev_U_cell(omega, g, a, U_N1, U_N2, scale);
    vec2 t_cell = cmul(t1, cexpi(omega * g.p1));
    return cdiv(r1 * U_N1, vec2(U_N1, 0.0) - U_N2 * t_cell);
}

// Appendix D: r_hN = (r_N + r_h1) / (1 + r_h1 r_N).
vec2 reflection_coefficient_host(vec2 r_N, vec2 r_h1) {
    return cdiv(r_N + r_h1, vec2(1.0, 0.0) + cmul(r_h1, r_N));
}

// Eq. 2 in real arithmetic (all waves propagate, nh = n1), from the half angles of the phases:
// |r1|^2 : |t1|^2 = 4 r12^2 sin^2 phi : (1 - r12^2)^2, their common denominator cancels.
float reflectance_real(vec4 h, CellGeometry g) {
    float r12_2 = g.r12.x * g.r12.x, sin_phi = sin_phi_of(h);
    float U_N1, U_N2, scale;
    chebyshev_U_half_angles(h, g.Omega.x, g.N, U_N1, U_N2, scale);
    float numerator = 4.0 * r12_2 * sin_phi * sin_phi * U_N1 * U_N1;
    return numerator / (numerator + (1.0 - r12_2) * (1.0 - r12_2) * scale * scale);
}

bool is_real_path(CellGeometry g) { return g.host_is_n1 && g.p1.y == 0.0 && g.p2.y == 0.0; }

float reflectance_polarised(float omega, CellGeometry g) {
    if (is_real_path(g)) return reflectance_real(half_angles(omega * g.p1.x, omega * g.p2.x), g);
    vec2 r1, t1;
    airy_slab_coefficients(omega, g, r1, t1);
    float a = cos_K_Lambda(omega, g);
    if (g.host_is_n1) return reflectance_yeh(r1, t1, a, g.N);  // an evanescent layer: complex phases
    return cabs2(reflection_coefficient_host(reflection_coefficient_bragg(r1, t1, omega, g, a), g.r_h1));
}

// Unpolarised R_lambda.
float bragg_reflectance(float cos_theta, float wavelength, BraggMirror mirror) {
    float omega = 2.0 * PI / wavelength;
    return 0.5 * (reflectance_polarised(omega, cell_geometry(cos_theta, mirror, 0)) +
                  reflectance_polarised(omega, cell_geometry(cos_theta, mirror, 1)));
}

// The spectral reference: R_lambda, both polarisations, sampled every 1/K nm with K = round(1 / step_nm),
// against the CMFs interpolated linearly (explorer/physics/bragg/reference.py, reference_rgb with a step; the samples'
// trapezoids against the hat functions of explorer/physics/colorimetry.py). step_nm = 1: the paper's sum over every
// nm from 360 to 830, which misses or hits the narrow resonances beside band edges for N of a few tens
// and more; a finer step converges towards the integral (numpy's reference_rgb without a step).
vec3 reference_rgb(float cos_theta, BraggMirror mirror, float step_nm) {
    CellGeometry g_s = cell_geometry(cos_theta, mirror, 0), g_p = cell_geometry(cos_theta, mirror, 1);
    int K = max(1, int(floor(1.0 / step_nm + 0.5)));
    float inverse_K = 1.0 / float(K);
    vec3 xyz = vec3(0.0);
    bool real = is_real_path(g_s);  // both polarisations then share the phases' trig
    // The hats' support is (359, 831) nm: its end samples have zero weight.
    for (int j = 1; j < (CMF_COUNT + 1) * K; ++j) {
        float wavelength = CMF_FIRST_WAVELENGTH - 1.0 + float(j) * inverse_K;
        float omega = 2.0 * PI / wavelength;
        float R;
        if (real) {
            vec4 h = half_angles(omega * g_s.p1.x, omega * g_s.p2.x);
            R = 0.5 * (reflectance_real(h, g_s) + reflectance_real(h, g_p));
        } else {
            R = 0.5 * (reflectance_polarised(omega, g_s) + reflectance_polarised(omega, g_p));
        }
        xyz += R * colour_matching_functions_at(wavelength);
    }
    return xyz_to_rgb(xyz * inverse_K);
}

// The paper's 1-nm sum.
vec3 reference_rgb(float cos_theta, BraggMirror mirror) { return reference_rgb(cos_theta, mirror, 1.0); }

// ---- Envelope and landmarks (Section 3.2.1, Appendices A, B) -------------------------------------

// Incoherent host interface over a mirror reflectance (our extension for nh != n1).
float under_host(float R_mirror, CellGeometry g) {
    if (g.host_is_n1) return R_mirror;
    float R_h1 = min(cabs2(g.r_h1), 1.0);  // 1 - (1 - R_h1)(1 - R) / (1 - R_h1 R): 1 when both reflect totally
    return 1.0 - (1.0 - R_h1) * (1.0 - R_mirror) / max(1.0 - R_h1 * R_mirror, 1e-30);
}

// Eq. 11.
float reflectance_envelope(float omega, CellGeometry g) {
    vec2 r1, t1;
    airy_slab_coefficients(omega, g, r1, t1);
    float a = cos_K_Lambda(omega, g);
    float r1_2 = cabs2(r1);
    float denominator = r1_2 + cabs2(t1) * max(1.0 - a * a, 0.0);
    return under_host(denominator > 0.0 ? r1_2 / denominator : 0.0, g);  // delta = 1: no cell, no gap
}

// R_h1 = |r_h1|^2, the host interface's reflectance (0 when the host is n1), at most 1.
float host_reflectance(CellGeometry g) { return g.host_is_n1 ? 0.0 : min(cabs2(g.r_h1), 1.0); }

// The paper's weight w~ R^e (Section 3.2.2, Appendix B); under a host, under_host(w~ R^e): w~ corrects the
// mirror's fringes, not the host interface's own reflection.
float paper_weight(float omega, CellGeometry g) {
    if (g.host_is_n1) return g.correction * reflectance_envelope(omega, g);
    vec2 r1, t1;
    airy_slab_coefficients(omega, g, r1, t1);
    float a = cos_K_Lambda(omega, g);
    float r1_2 = cabs2(r1);
    float denominator = r1_2 + cabs2(t1) * max(1.0 - a * a, 0.0);
    return under_host(g.correction * (denominator > 0.0 ? r1_2 / denominator : 0.0), g);
}

// |r_hN|^2 averaged over the fringes, coherently (Appendix D): r_hN = alpha + beta / (x - z) with x = cot(N K Lambda)
// spanning the real line with the Cauchy density 1 / (pi (1 + x^2)); <1 / (x - z)> = 1 / (-i sign(Im z) - z),
// <1 / |x - z|^2> = (1 + |q|) / (|q| ((1 + |q|)^2 + p^2)) for z = p + i q (explorer/physics/bragg/approximation.py has the derivation).
float fringe_average_under_host(vec2 r1, vec2 t1, float omega, CellGeometry g, float a) {
    vec2 t_cell = cmul(t1, cexpi(omega * g.p1));
    float sin_t = sqrt(max(1.0 - a * a, 0.0));
    vec2 A = vec2(1.0, 0.0) - a * t_cell, B = sin_t * t_cell;
    vec2 P = r1 + cmul(g.r_h1, A), Q = cmul(g.r_h1, B), S = A + cmul(g.r_h1, r1), T = B;
    // At a band edge (sin t -> 0) the fringes' weight vanishes: the limit |P / S|^2.
    if (cabs2(B) <= FRINGE_B_MIN) return clamp(cabs2(P) / max(cabs2(S), 1e-30), 0.0, 1.0);
    vec2 alpha = cdiv(Q, T), beta = cdiv(cmul(P, T) - cmul(Q, S), cmul(T, T)), z = -cdiv(S, T);
    float p = z.x, q = max(abs(z.y), FRINGE_Q_MIN);
    vec2 mean_pole = cinv(vec2(0.0, z.y > 0.0 ? -1.0 : 1.0) - z);
    float mean_pole_2 = (1.0 + q) / (q * ((1.0 + q) * (1.0 + q) + p * p));
    float average = cabs2(alpha) + 2.0 * cmul(cconj(alpha), cmul(beta, mean_pole)).x + cabs2(beta) * mean_pole_2;
    return clamp(average, 0.0, 1.0);
}

// Yeh's R averaged over its fringes: 1 - |sin K Lambda| / sqrt(|C|^2 + sin^2 K Lambda) (ours).
// Under a host nh != n1, the coherent average above.
float reflectance_fringe_average(float omega, CellGeometry g) {
    vec2 r1, t1;
    airy_slab_coefficients(omega, g, r1, t1);
    float a = cos_K_Lambda(omega, g);
    if (!g.host_is_n1) return fringe_average_under_host(r1, t1, omega, g, a);
    float t1_2_sin2 = cabs2(t1) * max(1.0 - a * a, 0.0);
    float denominator = cabs2(r1) + t1_2_sin2;
    return denominator > 0.0 ? 1.0 - sqrt(t1_2_sin2 / denominator) : 0.0;
}

// Appendix B: w~ = w~0 + (1 - w~0)(1 - cos theta_1)^5, w~0 = 0.735 R12 + 0.532.
float angular_correction(vec2 cos_theta_1, float n1, float n2) {
    float R12 = (n1 - n2) * (n1 - n2) / ((n1 + n2) * (n1 + n2));
    float w0 = 0.735 * R12 + 0.532;
    float m = 1.0 - clamp(cos_theta_1.x, 0.0, 1.0);
    return w0 + (1.0 - w0) * (m * m) * (m * m) * m;
}

float optical_thickness(CellGeometry g) { return max(g.p1.x + g.p2.x, 1e-9); }

// Eq. 13.
float mode_frequency(float m, float n_plus) { return m * PI / n_plus; }

float airy_point(CellGeometry g, float lo, float hi, float m) {
    bool positive_at_lo = mod(m, 2.0) < 0.5;  // cos K Lambda has the sign (-1)^m at omega_m (Appendix A)
    for (int i = 0; i < BISECTION_STEPS; ++i) {
        float mid = 0.5 * (lo + hi);
        if ((cos_K_Lambda(mid, g) >= 0.0) == positive_at_lo) lo = mid; else hi = mid;
    }
    return 0.5 * (lo + hi);
}

float band_edge(CellGeometry g, float lo, float hi, bool gap_at_lo) {
    for (int i = 0; i < BISECTION_STEPS; ++i) {
        float mid = 0.5 * (lo + hi);
        if ((abs(cos_K_Lambda(mid, g)) - 1.0 >= 0.0) == gap_at_lo) lo = mid; else hi = mid;
    }
    return 0.5 * (lo + hi);
}

// Eq. 12: the first zero point above omega (none while n2 is evanescent).
float zero_point_after(CellGeometry g, float omega, out bool exists) {
    exists = g.p2.y == 0.0 && g.p2.x > 0.0;
    float p2 = exists ? g.p2.x : 1.0;
    return (floor(omega * p2 / PI) + 1.0) * PI / p2;
}

// ---- The piecewise-constant approximation (Section 3.2.2) ----------------------------------------

float wavelength_of(float omega) { return 2.0 * PI / max(omega, 1e-9); }

// max(1, s - m), m counted from the first visible interval (relative) or from mode 0 (absolute).
float subdivisions(float m, float m_first, float s, bool absolute_numbering) {
    if (s <= 0.0) return 1.0;
    return max(1.0, s - (absolute_numbering ? m : m - m_first));
}

// Sub-boxes of the improved variant (ours): ceil(4 s mu), mu the box's share of the visible CMF mass,
// from the C values at the box's ends.
float subdivisions_by_mass(vec3 C_low, vec3 C_high, float s) {
    if (s <= 0.0) return 1.0;
    float total = dot(cmf_cumulative_at(WAVELENGTH_HIGH), vec3(1.0));
    return max(1.0, ceil(4.0 * s * dot(C_low - C_high, vec3(1.0)) / total));
}

// The improved variant (ours) resolves a pass band's fringes where, in its visible part, a fringe feature
// is wider than FRINGE_RESOLVE_NM / s nm (times (N / N_RESOLVE)^GROW_EXPONENT beyond N_RESOLVE cells) and
// SAMPLES_PER_FRINGE N <= RESOLVE_BUDGET, with SAMPLES_PER_FRINGE sub-boxes per feature weighted by the
// exact reflectance (explorer/physics/bragg/approximation.py has the reasoning).

// Fringes of Eq. 2 in a pass-band box: N |Delta K Lambda| / pi.
// The Bloch phase K Lambda in [0, pi] (Eq. 8); at a band edge exactly 0 or pi by the sign of cos K Lambda (acos is
// ill-conditioned there: float32's rounding of a bisected edge would move the fringe count, a step of the colour).
float bloch_phase(float omega, CellGeometry g, bool at_edge) {
    float a = cos_K_Lambda(omega, g);
    if (at_edge) return a >= 0.0 ? 0.0 : PI;
    return acos(clamp(a, -1.0, 1.0));
}

float fringe_count(float omega_low, float omega_high, CellGeometry g, bool low_at_edge, bool high_at_edge) {
    float t_low = bloch_phase(omega_low, g, low_at_edge);
    float t_high = bloch_phase(omega_high, g, high_at_edge);
    return g.N * abs(t_high - t_low) / PI;
}

// The share of a fringe its dip fills at most: min(1, 2 / (pi sqrt(k))), k >= 4 r12^2 / (1 - r12^2)^2 and R_h1 / (1 - R_h1).
float fringe_sharpness(CellGeometry g) {
    float r12_2 = min(cabs2(g.r12), 1.0 - 1e-7);
    float k = 4.0 * r12_2 / ((1.0 - r12_2) * (1.0 - r12_2));
    float R_h1 = min(host_reflectance(g), 1.0 - 1e-7);
    k = max(k, R_h1 / (1.0 - R_h1));
    return min(1.0, 2.0 / (PI * sqrt(max(k, 1e-30))));
}

bool fringes_resolved(float edge_low, float edge_high, float s, CellGeometry g) {
    if (s <= 0.0 || SAMPLES_PER_FRINGE * g.N > RESOLVE_BUDGET) return false;
    float low = max(edge_low, OMEGA_LOW), high = min(edge_high, OMEGA_HIGH);  // the pass band's visible part
    if (high <= low) return false;
    float fringes = max(fringe_count(low, high, g, edge_low >= OMEGA_LOW, edge_high <= OMEGA_HIGH), 1e-9);
    float width_nm = wavelength_of(low) - wavelength_of(high);
    float grow = pow(max(1.0, g.N / N_RESOLVE), GROW_EXPONENT);
    return width_nm * fringe_sharpness(g) * s > FRINGE_RESOLVE_NM * grow * fringes;
}

float subdivisions_resolving_fringes(float omega_low, float omega_high, vec3 C_low, vec3 C_high, float s, CellGeometry g, bool resolved,
                                     int edge) {
    float by_mass = subdivisions_by_mass(C_low, C_high, s);
    if (!resolved) return by_mass;
    float fringes = fringe_count(omega_low, omega_high, g, edge < 0, edge > 0);
    float pieces = min(ceil(SAMPLES_PER_FRINGE * fringes / fringe_sharpness(g)), MAX_RESOLVED_PIECES);
    return max(pieces, by_mass);
}

// The exact reflectance where fringes are resolved (Eqs. 2, 9; Appendix D under a host), their closed-form
// average otherwise: one airy_slab_coefficients and cos_K_Lambda for both, so that the exact branch adds
// little code to the loop (llvmpipe pays for a branch's code even where no pixel takes it).
float pass_band_weight(float omega, CellGeometry g, bool resolved) {
    vec2 r1, t1;
    airy_slab_coefficients(omega, g, r1, t1);
    float a = cos_K_Lambda(omega, g);
    if (resolved) {
        float U_N1, U_N2, scale;
        chebyshev_U(a, g.N, U_N1, U_N2, scale);
        if (g.host_is_n1) {
            float numerator = cabs2(r1) * U_N1 * U_N1;
            return numerator / max(numerator + cabs2(t1) * scale * scale, 1e-30);
        }
        vec2 r_N = cdiv(r1 * U_N1, vec2(U_N1, 0.0) - U_N2 * cmul(t1, cexpi(omega * g.p1)));
        return clamp(cabs2(reflection_coefficient_host(r_N, g.r_h1)), 0.0, 1.0);
    }
    if (!g.host_is_n1) return fringe_average_under_host(r1, t1, omega, g, a);
    float t1_2_sin2 = cabs2(t1) * max(1.0 - a * a, 0.0);
    float denominator = cabs2(r1) + t1_2_sin2;
    return denominator > 0.0 ? 1.0 - sqrt(t1_2_sin2 / denominator) : 0.0;
}

// A half band gap's weight (ours): the exact reflectance at its middle (the paper's 1 is its large-N limit).
float gap_weight(float omega_low, float omega_high, CellGeometry g) {
    return pass_band_weight(0.5 * (omega_low + omega_high), g, true);
}

// Sub-box j of pieces in [lo, hi]: equal (edge 0), or graded quadratically toward a band edge at lo
// (edge -1) or hi (edge +1) and sampled at its centroid (ours).
void sub_box(float lo, float hi, float j, float pieces, int edge, out float sub_lo, out float centre, out float sub_hi) {
    float u0 = j / pieces, u1 = (j + 1.0) / pieces, width = hi - lo;
    if (edge == 0) {
        sub_lo = lo + width * u0; centre = lo + width * 0.5 * (u0 + u1); sub_hi = lo + width * u1;
        return;
    }
    float uc = 2.0 * (u0 * u0 + u0 * u1 + u1 * u1) / (3.0 * (u0 + u1));
    if (edge < 0) {
        sub_lo = lo + width * u0 * u0; centre = lo + width * uc * uc; sub_hi = lo + width * u1 * u1;
    } else {
        sub_lo = hi - width * u1 * u1; centre = hi - width * uc * uc; sub_hi = hi - width * u0 * u0;
    }
}

// Eq. 15 for one polarisation: boxes walked in increasing omega, one C lookup per landmark (Eq. 16).
vec3 approximate_xyz_polarised(CellGeometry g, float s, bool absolute_numbering, bool improved) {
    float n_plus = optical_thickness(g);
    float m_first = floor(OMEGA_LOW * n_plus / PI), m_last = floor(OMEGA_HIGH * n_plus / PI);
    vec3 xyz = vec3(0.0);
    for (float m = m_first; m <= m_last; m += 1.0) {
        float omega_m = mode_frequency(m, n_plus);
        float omega_next = min(mode_frequency(m + 1.0, n_plus), OMEGA_HIGH);
        float omega_a = airy_point(g, omega_m, omega_next, m);
        float edge_low = band_edge(g, omega_m, omega_a, true);
        float edge_high = band_edge(g, omega_a, omega_next, false);
        bool has_zero;
        float omega_z = zero_point_after(g, edge_low, has_zero);
        float z = has_zero && omega_z < edge_high ? omega_z : omega_a;
        float x1 = min(z, omega_a), x2 = max(z, omega_a);

        vec3 C_previous = cmf_cumulative_at(wavelength_of(omega_m));
        vec3 C_next = cmf_cumulative_at(wavelength_of(edge_low));
        // Resolved fringes (ours): the gaps take their finite-N reflectance too, else w = 1 (the paper).
        bool resolved = improved && fringes_resolved(edge_low, edge_high, s, g);
        float gap = 1.0;
        if (resolved) gap = gap_weight(omega_m, edge_low, g);
        xyz += gap * (C_previous - C_next);  // upper half of the gap around mode m
        C_previous = C_next;
        float pieces = subdivisions(m, m_first, s, absolute_numbering);
        for (int box = 0; box < 3; ++box) {
            float lo = box == 0 ? edge_low : (box == 1 ? x1 : x2);
            float hi = box == 0 ? x1 : (box == 1 ? x2 : edge_high);
            if (hi <= lo) continue;
            int edge = improved ? box - 1 : 0;
            vec3 C_high = cmf_cumulative_at(wavelength_of(hi));
            if (improved) pieces = subdivisions_resolving_fringes(lo, hi, C_previous, C_high, s, g, resolved, edge);
            for (float k = 0.0; k < pieces; k += 1.0) {
                float j = edge > 0 ? pieces - 1.0 - k : k;  // keep omega increasing
                float sub_lo, centre, sub_hi;
                sub_box(lo, hi, j, pieces, edge, sub_lo, centre, sub_hi);
                float weight;
                if (improved) weight = pass_band_weight(centre, g, resolved);
                else weight = paper_weight(centre, g);
                C_next = k + 1.0 < pieces ? cmf_cumulative_at(wavelength_of(sub_hi)) : C_high;
                xyz += weight * (C_previous - C_next);
                C_previous = C_next;
            }
        }
        // lower half of the next gap
        gap = 1.0;
        if (resolved) gap = gap_weight(edge_high, omega_next, g);
        xyz += gap * (C_previous - cmf_cumulative_at(wavelength_of(omega_next)));
    }
    return xyz;
}

// Section 3.2: s = 0 basic, s >= 1 subdivided; improved = our variant.
vec3 approximate_rgb(float cos_theta, BraggMirror mirror, float s, bool absolute_numbering, bool improved) {
    vec3 xyz = approximate_xyz_polarised(cell_geometry(cos_theta, mirror, 0), s, absolute_numbering, improved) +
               approximate_xyz_polarised(cell_geometry(cos_theta, mirror, 1), s, absolute_numbering, improved);
    return xyz_to_rgb(0.5 * xyz);
}

// The tabulated method: exact RGB over cos theta in [0, 1], table entry k at cos theta = k / (size - 1).
// Two texel fetches interpolated in float: the numpy twin's arithmetic (hardware filtering may round its
// weights to 8 bits), and cheaper than a filtered fetch on llvmpipe (bench --tables).
vec3 tabulated_rgb(sampler2D table, float cos_theta) {
    int last = textureSize(table, 0).x - 1;
    float x = clamp(cos_theta, 0.0, 1.0) * float(last);
    int i = clamp(int(x), 0, max(last - 1, 0));  // a 1-texel placeholder reads its texel
    return mix(texelFetch(table, ivec2(i, 0), 0).rgb, texelFetch(table, ivec2(min(i + 1, last), 0), 0).rgb, x - float(i));
}

#ifdef TABLE_BUFFERS
// The table packed one interval a texel (what the host uploads for a usamplerBuffer): words 0-2 hold R, G, B
// of entries i and i + 1 as signed 16-bit codes (low, high half), word 3 the interval's float scale. One
// fetch a lookup (llvmpipe calls out of line for each), ~20% less CPU than two float texels; entries within
// 1.53e-5 of the interval's largest |channel|, mixed in float. Twin: explorer.gpu.packed_tables.packed_tabulated_rgb.
vec3 packed_tabulated_rgb(usamplerBuffer table, float cos_theta) {
    int intervals = textureSize(table);
    float x = clamp(cos_theta, 0.0, 1.0) * float(intervals);
    int i = min(int(x), intervals - 1);
    uvec4 texel = texelFetch(table, i);
    ivec3 start = ivec3(texel.xyz << 16) >> 16;  // GLSL's >> on int extends the sign
    ivec3 end = ivec3(texel.xyz) >> 16;
    return uintBitsToFloat(texel.w) * mix(vec3(start), vec3(end), x - float(i));
}

vec3 tabulated_rgb(usamplerBuffer table, float cos_theta) { return packed_tabulated_rgb(table, cos_theta); }
#endif

// Supplemental Figure 7: a mirror whose Lambda and delta follow a texture value T in [0, 1], mapping's bits
// 1: Lambda (0.5 + 0.5 T), 2: delta^T (delta^0 = 1; GLSL's pow(0, 0) is undefined). Twin: explorer.physics.bragg.textured_mirror.
BraggMirror textured_mirror(BraggMirror mirror, float T, int mapping) {
    T = clamp(T, 0.0, 1.0);
    if ((mapping & 1) != 0) mirror.Lambda *= 0.5 + 0.5 * T;
    if ((mapping & 2) != 0) mirror.delta = T <= 0.0 ? 1.0 : pow(mirror.delta, T);
    return mirror;
}

// Only in the views that read a surface texture (the host defines SURFACE_TEXTURE): no sampler in a .brdf export.
#ifdef SURFACE_TEXTURE
#include "lib/structure_maps.glsl"

// Structure maps (lib/structure_maps.glsl): the texel's mirror, its fields (n1, n2, Lambda, delta) and (N, nh) in the
// order of explorer.physics.bragg.STRUCTURE_FIELDS; false off the maps' mask. Twin: explorer.physics.bragg.mapped_mirrors.
bool mapped_mirror(sampler2D table, float T, out BraggMirror mirror) {
    vec4 a, b;
    bool inside = structure_texels(table, T, a, b);
    mirror = BraggMirror(a.x, a.y, a.z, a.w, max(b.x, 1.0), b.y);
    return inside;
}

// The tabulated method of a textured mirror: the table over (cos theta across, T down), rows at T = k / (rows - 1),
// bilinear between four texels in float (as tabulated_rgb). Twin: explorer.physics.bragg.textured_tabulated_rgb.
vec3 textured_tabulated_rgb(sampler2D table, float cos_theta, float T) {
    ivec2 last = textureSize(table, 0) - 1;
    float x = clamp(cos_theta, 0.0, 1.0) * float(last.x);
    float y = clamp(T, 0.0, 1.0) * float(last.y);
    int i = clamp(int(x), 0, max(last.x - 1, 0));
    int j = clamp(int(y), 0, max(last.y - 1, 0));
    vec3 top = mix(texelFetch(table, ivec2(i, j), 0).rgb, texelFetch(table, ivec2(min(i + 1, last.x), j), 0).rgb, x - float(i));
    vec3 bottom = mix(texelFetch(table, ivec2(i, min(j + 1, last.y)), 0).rgb, texelFetch(table, ivec2(min(i + 1, last.x), min(j + 1, last.y)), 0).rgb, x - float(i));
    return mix(top, bottom, y - float(j));
}
#endif
