// Belcour's (2018) atomic decomposition of layered materials: twin of explorer/physics/lobes.py (Bati, Barla &
// Pacanowski 2021, Section 4: Eqs. 2-6, BRDF Eq. 3). Energies per polarisation (s, p) and RGB channel,
// variances per channel; the host binds luts/lobes_fgd_correction.npy as lobes_fgd (rows eta-major,
// alpha-minor; columns cos theta; the unpolarised FGD - F in red) and luts/lobes_ggx_moments.npy as lobes_ggx_moments
// (rows alpha; columns cos theta; channels E, cbar_d). All lookups are texelFetch + explicit trilinear
// weights, the numpy twin's arithmetic.
#include "lib/complex.glsl"
#include "lib/microfacet.glsl"

#include "generated/lobes.glsl"  // the constants shared with explorer/physics (generated at assembly)

// A stack (Bati et al., Table 1): medium i has index eta[i] (eta[0] the ambient), optical depth tau[i];
// interface i (top of medium i) roughness alpha[i]. The base (medium count) is a conductor of index
// eta_base + i kappa_base when conductor is set.
struct LobeStack {
    int count;
    float eta[LOBES_MAX + 1];
    float alpha[LOBES_MAX + 1];
    vec3 tau[LOBES_MAX + 1];
    bool conductor;
    bool tir;            // explorer.physics.lobes.Stack.tir: light going up sees the FGD of its own side
    vec3 eta_base;
    vec3 kappa_base;
};

float variance_from_roughness(float alpha) {
    float a = pow(clamp(alpha, 0.0, 1.0), 1.1);
    return min(a / max(1.0 - a, 1.0 / VARIANCE_MAX), VARIANCE_MAX);
}
vec3 roughness_from_variance(vec3 sigma) {
    vec3 s = clamp(sigma, 0.0, VARIANCE_MAX);
    return mix(pow(s / (1.0 + s), vec3(1.0 / 1.1)), vec3(1.0), greaterThanEqual(s, vec3(VARIANCE_MAX)));
}

// [R_s, R_p] of a smooth dielectric interface of relative index eta; 1 beyond the critical angle.
// For eta > 1 in terms of u = 1 / eta, so a huge index (eta^2 overflows float32 from 1.8e19) gives
// numpy's float64 answer, |r| -> 1.
vec2 fresnel_sp(float cos_theta, float eta) {
    float c = clamp(cos_theta, 0.0, 1.0), s2 = 1.0 - c * c;
    if (eta > 1.0) {
        float u = 1.0 / eta, w = sqrt(max(1.0 - s2 * u * u, 0.0));  // w = cos theta_t
        float rs = (c * u - w) / (c * u + w), rp = (c - u * w) / max(c + u * w, 1e-30);
        return c + u * w > 0.0 ? vec2(rs * rs, rp * rp) : vec2(1.0);
    }
    float n2 = eta * eta;
    float q2 = n2 - s2;
    if (q2 <= 0.0) return vec2(1.0);
    float q = sqrt(q2);  // eta cos theta_t
    float rs = (c - q) / max(c + q, 1e-30), rp = (n2 * c - q) / max(n2 * c + q, 1e-30);
    return c + q > 0.0 ? vec2(rs * rs, rp * rp) : vec2(1.0);
}

// The principal square root (Re >= 0) of z.
vec2 csqrt_principal(vec2 z) {
    float m = max(abs(z.x), abs(z.y)), r = m > 0.0 ? m * length(z / m) : 0.0;  // |z| without overflow
    return vec2(sqrt(max(0.5 * (r + z.x), 0.0)), sqrt(max(0.5 * (r - z.x), 0.0)) * (z.y < 0.0 ? -1.0 : 1.0));
}

// The same towards a conductor n = eta + i kappa (relative indices). With u = 1 / n and
// w = cos theta_t = sqrt(1 - sin^2 u^2): r_s = (c u - w) / (c u + w), r_p = (c - u w) / (c + u w), the
// forms of (c - q) / (c + q) and (n^2 c - q) / (n^2 c + q) (q = n w) whose parts stay within float32 for
// any |n| >= 1 (eta_base = 1e10 would overflow n^2 |n|^2); below, the direct forms.
vec2 fresnel_sp_conductor(float cos_theta, float eta, float kappa) {
    float c = clamp(cos_theta, 0.0, 1.0), s2 = 1.0 - c * c;
    vec2 n = vec2(eta, kappa);
    vec2 rs, rp;
    if (max(abs(eta), abs(kappa)) >= 1.0) {
        vec2 u = cinv_scaled(n);
        vec2 w = csqrt_principal(vec2(1.0, 0.0) - s2 * cmul(u, u));
        vec2 uw = cmul(u, w);
        rs = cdiv_scaled(c * u - w, c * u + w);
        rp = cdiv_scaled(vec2(c, 0.0) - uw, vec2(c, 0.0) + uw);
    } else {
        vec2 n2 = cmul(n, n);
        vec2 q = csqrt_principal(n2 - vec2(s2, 0.0));
        rs = cdiv(vec2(c, 0.0) - q, vec2(c, 0.0) + q);
        rp = cdiv(c * n2 - q, c * n2 + q);
    }
    return vec2(cabs2(rs), cabs2(rp));
}

// Node index and fraction on count uniform nodes over [lo, hi], clamped (explorer.physics.lobes._axis).
void lobes_axis(float value, int count, float lo, float hi, out int i, out float f) {
    float x = (clamp(value, lo, hi) - lo) / (hi - lo) * float(count - 1);
    i = min(int(floor(x)), count - 2);
    f = x - float(i);
}

// The table's warped cosine (explorer.physics.lobes.fgd_cos_coordinate): the critical angle of eta < 1 at t = 1/2,
// sqrt(cos theta - cos theta_c) above it (where Fresnel is smooth).
float fgd_cos_coordinate(float cos_theta, float eta) {
    float c = clamp(cos_theta, 0.0, 1.0), c_c = sqrt(max(1.0 - eta * eta, 0.0));
    if (c_c <= 0.0) return c;
    return c <= c_c ? 0.5 * c / max(c_c, 1e-12) : 0.5 + 0.5 * sqrt(max(c - c_c, 0.0) / max(1.0 - c_c, 1e-12));
}

// FGD of a rough dielectric interface: exact Fresnel per polarisation plus the tabulated (unpolarised) correction.
vec2 fgd_dielectric(sampler2D table, float cos_theta, float alpha, float eta) {
    int ic, ia, ie;
    float fc, fa, fe;
    lobes_axis(fgd_cos_coordinate(cos_theta, eta), FGD_COS_COUNT, 0.0, 1.0, ic, fc);
    lobes_axis(alpha, FGD_ALPHA_COUNT, 0.0, 1.0, ia, fa);
    lobes_axis(log(max(eta, 1e-12)) / log(ETA_TABLE_MAX), FGD_ETA_COUNT, -1.0, 1.0, ie, fe);
    float correction = 0.0;
    for (int de = 0; de < 2; ++de) {
        for (int da = 0; da < 2; ++da) {
            int row = (ie + de) * FGD_ALPHA_COUNT + ia + da;
            float w = (de == 0 ? 1.0 - fe : fe) * (da == 0 ? 1.0 - fa : fa);
            correction += w * ((1.0 - fc) * texelFetch(table, ivec2(ic, row), 0).r + fc * texelFetch(table, ivec2(ic + 1, row), 0).r);
        }
    }
    // Shared by s and p in proportion to their reflectances where FGD < F, to their transmittances where
    // FGD > F: both stay in [0, 1] (explorer.physics.lobes.fgd_dielectric).
    vec2 F = fresnel_sp(cos_theta, eta);
    float mean = 0.5 * (F.x + F.y);
    float target = clamp(mean + correction, 0.0, 1.0);
    vec2 R = target <= mean ? F * (mean > 0.0 ? target / mean : 1.0) : 1.0 - (1.0 - F) * (mean < 1.0 ? (1.0 - target) / (1.0 - mean) : 1.0);
    return clamp(R, 0.0, 1.0);  // rounding only
}

// FGD of a rough conductor: the lobe's albedo E times Fresnel at its mean half-angle cosine.
vec2 fgd_conductor(sampler2D moments, float cos_theta, float alpha, float eta, float kappa) {
    int ic, ia;
    float fc, fa;
    lobes_axis(cos_theta, FGD_COS_COUNT, 0.0, 1.0, ic, fc);
    lobes_axis(alpha, FGD_ALPHA_COUNT, 0.0, 1.0, ia, fa);
    vec2 m = (1.0 - fa) * ((1.0 - fc) * texelFetch(moments, ivec2(ic, ia), 0).rg + fc * texelFetch(moments, ivec2(ic + 1, ia), 0).rg)
           + fa * ((1.0 - fc) * texelFetch(moments, ivec2(ic, ia + 1), 0).rg + fc * texelFetch(moments, ivec2(ic + 1, ia + 1), 0).rg);
    return clamp(m.x * fresnel_sp_conductor(m.y, eta, kappa), 0.0, 1.0);
}

// The adding equations (explorer.physics.lobes.lobes_and_statistics): lobe energies R_k and variances sigma_k at
// incidence cos_theta, k < s.count (the others 0). Rs/Rp: energies per polarisation.
void lobes(LobeStack s, sampler2D fgd_table, sampler2D moments, float cos_theta, out vec3 energy[LOBES_MAX], out vec3 variance[LOBES_MAX]) {
    float c = clamp(cos_theta, LOBES_COS_MIN, 1.0);
    vec3 R0n_s = vec3(0.0), R0n_p = vec3(0.0), Rn0_s = vec3(0.0), Rn0_p = vec3(0.0);
    vec3 T0n_s = vec3(1.0), T0n_p = vec3(1.0), Tn0_s = vec3(1.0), Tn0_p = vec3(1.0);
    vec3 s_rn0 = vec3(0.0), s_t0n = vec3(0.0), s_tn0 = vec3(0.0);
    float j_0n = 1.0;
    for (int k = 0; k < LOBES_MAX; ++k) { energy[k] = vec3(0.0); variance[k] = vec3(0.0); }
    for (int i = 1; i <= LOBES_MAX; ++i) {
        if (i > s.count) break;
        bool conductor = s.conductor && i == s.count;
        float n12 = (conductor ? dot(s.eta_base, vec3(1.0 / 3.0)) : s.eta[i]) / s.eta[i - 1];
        float sin_t = sqrt(max(1.0 - c * c, 0.0)) / n12;
        bool transmits = sin_t < 1.0 && !conductor;
        float c_t = max(transmits ? sqrt(max(1.0 - sin_t * sin_t, 0.0)) : c, LOBES_COS_MIN);
        vec3 attenuation = i > 1 ? exp(-s.tau[i - 1] / c) : vec3(1.0);
        vec3 a2 = attenuation * attenuation;
        float alpha = s.alpha[i];
        float s_r12 = variance_from_roughness(alpha);
        float s_t12 = variance_from_roughness(0.5 * abs(1.0 - 1.0 / n12) * alpha);  // Eq. 6
        float s_t21 = variance_from_roughness(0.5 * abs(1.0 - n12) * alpha);
        vec3 alpha_eff = roughness_from_variance(s_t0n + s_r12);
        vec3 R12_s, R12_p;
        for (int ch = 0; ch < 3; ++ch) {
            vec2 F = conductor
                ? fgd_conductor(moments, c, alpha_eff[ch], s.eta_base[ch] / s.eta[i - 1], s.kappa_base[ch] / s.eta[i - 1])
                : fgd_dielectric(fgd_table, c, alpha_eff[ch], n12);
            R12_s[ch] = F.x;
            R12_p[ch] = F.y;
        }
        vec3 T12_s = conductor ? vec3(0.0) : 1.0 - R12_s, T12_p = conductor ? vec3(0.0) : 1.0 - R12_p;
        vec3 R21_s = R12_s, R21_p = R12_p;
        if (s.tir && transmits) {
            for (int ch = 0; ch < 3; ++ch) {
                vec2 F = fgd_dielectric(fgd_table, c_t, alpha_eff[ch], 1.0 / n12);
                R21_s[ch] = F.x;
                R21_p[ch] = F.y;
            }
        }
        vec3 T21_s = conductor ? vec3(0.0) : 1.0 - R21_s, T21_p = conductor ? vec3(0.0) : 1.0 - R21_p;
        float j12 = transmits ? c_t * n12 / c : 1.0;
        vec3 x_s = a2 * R12_s * Rn0_s, x_p = a2 * R12_p * Rn0_p;
        vec3 D_s = 1.0 - x_s, D_p = 1.0 - x_p;
        vec3 E_s = T0n_s * a2 * R12_s * Tn0_s / D_s, E_p = T0n_p * a2 * R12_p * Tn0_p / D_p;  // Eqs. 2, 17
        vec3 m_rr = 0.5 * (x_s / D_s + x_p / D_p);
        energy[i - 1] = 0.5 * (E_s + E_p);
        variance[i - 1] = s_tn0 + j_0n * (s_t0n + s_r12 + m_rr * (s_r12 + s_rn0));  // Eqs. 4-5
        if (!transmits || i == s.count) break;
        vec3 m_ri0_s = T21_s * a2 * Rn0_s * T12_s / D_s, m_ri0_p = T21_p * a2 * Rn0_p * T12_p / D_p;
        vec3 Rn0_new_s = R21_s + m_ri0_s, Rn0_new_p = R21_p + m_ri0_p;
        vec3 Rn0_mean = 0.5 * (Rn0_new_s + Rn0_new_p);
        vec3 s_t0n_new = (s_t0n + m_rr * (s_r12 + s_rn0)) / j12 + s_t12;
        s_tn0 = s_tn0 + j_0n * (s_t21 + m_rr * (s_r12 + s_rn0));
        vec3 numerator = 0.5 * (R21_s + R21_p) * s_r12 + 0.5 * (m_ri0_s + m_ri0_p) * (s_t12 + (s_t21 + s_rn0 + m_rr * (s_r12 + s_rn0)) / j12);
        s_rn0 = mix(vec3(0.0), numerator / max(Rn0_mean, vec3(1e-30)), greaterThan(Rn0_mean, vec3(0.0)));
        s_t0n = s_t0n_new;
        T0n_s = T0n_s * attenuation * T12_s / D_s;
        T0n_p = T0n_p * attenuation * T12_p / D_p;
        Tn0_s = T21_s * attenuation * Tn0_s / D_s;
        Tn0_p = T21_p * attenuation * Tn0_p / D_p;
        Rn0_s = Rn0_new_s;
        Rn0_p = Rn0_new_p;
        j_0n *= j12;
        c = c_t;
    }
}

// The stack's total reflected energy sum_k R_k (the gradient and sphere views).
vec3 lobes_reflectance(LobeStack s, sampler2D fgd_table, sampler2D moments, float cos_theta) {
    vec3 energy[LOBES_MAX], variance[LOBES_MAX];
    lobes(s, fgd_table, moments, cos_theta, energy, variance);
    return energy[0] + energy[1] + energy[2] + energy[3];
}

// GGX lobe without Fresnel, per channel: D(h) G1(i) G1(o) / (4 cos_i cos_o).
vec3 ggx_lobe_rgb(float cos_i, float cos_o, float cos_h, vec3 alpha) {
    vec3 result;
    for (int ch = 0; ch < 3; ++ch)
        result[ch] = 0.25 * ggx_D(cos_h, alpha[ch]) * smith_G1_over_cos(cos_i, alpha[ch]) * smith_G1_over_cos(cos_o, alpha[ch]);
    return result;
}

// Eq. 3: sum_k R_k(theta_0) rho_k(f^-1(sigma_k(theta_0)), L, V), theta_0 the light's angle.
vec3 lobes_brdf(LobeStack s, sampler2D fgd_table, sampler2D moments, vec3 L, vec3 V, vec3 N) {
    float cos_i = dot(L, N), cos_o = dot(V, N);
    if (cos_i <= 0.0 || cos_o <= 0.0) return vec3(0.0);
    float cos_h = dot(half_vector(L, V, N), N);
    vec3 energy[LOBES_MAX], variance[LOBES_MAX];
    lobes(s, fgd_table, moments, cos_i, energy, variance);
    vec3 result = vec3(0.0);
    for (int k = 0; k < LOBES_MAX; ++k) {
        if (k >= s.count) break;
        result += energy[k] * ggx_lobe_rgb(cos_i, cos_o, cos_h, roughness_from_variance(variance[k]));
    }
    return result;
}
