// Monte Carlo sampling for the env view (shaders/views/env.glsl): a hash for random numbers, cosine and
// GGX visible-normal sampling and their densities. Twins: explorer/physics/microfacet.py (sample_ggx_visible_normal,
// ggx_visible_normal_pdf, ggx_reflection_pdf) and explorer/views/env.py (pcg4d, sample_cosine_hemisphere).
// GGX's D and G1 come from lib/microfacet.glsl (its PI is a macro that a material's own PI does not clash with).
#include "lib/microfacet.glsl"

// PCG4D (Jarzynski & Olano 2020, Hash Functions for GPU Rendering, JCGT 9(3)): four well-mixed 32-bit
// words from four inputs (pixel x, pixel y, sample, seed).
uvec4 pcg4d(uvec4 v) {
    v = v * 1664525u + 1013904223u;
    v.x += v.y * v.w; v.y += v.z * v.x; v.z += v.x * v.y; v.w += v.y * v.z;
    v ^= v >> 16u;
    v.x += v.y * v.w; v.y += v.z * v.x; v.z += v.x * v.y; v.w += v.y * v.z;
    return v;
}

// The top 24 bits as floats in [0, 1): exact in float32, never 1.
vec4 uniform_floats(uvec4 h) { return vec4(h >> 8u) * (1.0 / 16777216.0); }

// An orthonormal basis (t, b, n) around the unit n (Duff et al. 2017, Building an Orthonormal Basis,
// Revisited, JCGT 6(1)): continuous everywhere except n.z = -1 exactly.
void sampling_basis(vec3 n, out vec3 t, out vec3 b) {
    float s = n.z >= 0.0 ? 1.0 : -1.0;
    float a = -1.0 / (s + n.z);
    float c = n.x * n.y * a;
    t = vec3(1.0 + s * n.x * n.x * a, s * c, -s * n.x);
    b = vec3(c, s + n.y * n.y * a, -n.y);
}

// Cosine-distributed direction about +z (Malley's method): density cos(theta) / pi.
vec3 sample_cosine_hemisphere(vec2 u) {
    float r = sqrt(u.x), phi = 2.0 * PI * u.y;
    return vec3(r * cos(phi), r * sin(phi), sqrt(max(0.0, 1.0 - u.x)));
}

// A GGX normal visible from v (local frame, n = +z, v.z > 0): Heitz 2018, Sampling the GGX Distribution of
// Visible Normals, JCGT 7(4), Listing 1. Density: ggx_visible_normal_pdf.
vec3 sample_ggx_visible_normal(vec3 v, float alpha, vec2 u) {
    float a = max(alpha, ALPHA_MIN);
    vec3 vh = normalize(vec3(a * v.x, a * v.y, v.z));
    float lensq = vh.x * vh.x + vh.y * vh.y;
    vec3 t1_axis = lensq > 0.0 ? vec3(-vh.y, vh.x, 0.0) * inversesqrt(lensq) : vec3(1.0, 0.0, 0.0);
    vec3 t2_axis = cross(vh, t1_axis);
    float r = sqrt(u.x), phi = 2.0 * PI * u.y;
    float t1 = r * cos(phi), t2 = r * sin(phi);
    float s = 0.5 * (1.0 + vh.z);
    t2 = (1.0 - s) * sqrt(max(0.0, 1.0 - t1 * t1)) + s * t2;
    vec3 nh = t1 * t1_axis + t2 * t2_axis + sqrt(max(0.0, 1.0 - t1 * t1 - t2 * t2)) * vh;
    return normalize(vec3(a * nh.x, a * nh.y, max(0.0, nh.z)));
}

// D_v(m) = G1(v) max(0, v.m) D(m) / v.n (Heitz 2018, Eq. 1), local frame.
float ggx_visible_normal_pdf(vec3 v, vec3 m, float alpha) {
    return smith_G1_over_cos(v.z, alpha) * max(0.0, dot(v, m)) * ggx_D(m.z, alpha);
}

// Density of l = reflect(-v, m), m ~ D_v, about the unit normal N (any frame): D_v(h) / (4 v.h) =
// G1(v) D(h) / (4 v.N) with h = (l + v) / |l + v| (Walter et al. 2007, Eq. 14). h is computed as
// microfacet_lobe(l, v, ...) computes it (lib/microfacet.glsl), to the same float32 bits: for alpha near 0,
// D(h) is ~1 / (pi alpha^2) at cos = 1 and orders of magnitude less one rounding away, so the BRDF's D and
// this one must round alike for their ratio to stay finite.
float ggx_reflection_pdf(vec3 l, vec3 v, vec3 N, float alpha) {
    vec3 s = l + v;
    float norm = length(s);
    if (norm <= 1e-12) return 0.0;
    vec3 h = s / norm;
    return 0.25 * smith_G1_over_cos(dot(v, N), alpha) * ggx_D(dot(h, N), alpha);
}

// Environment importance sampling (Pharr, Jakob & Humphreys, PBRT 3rd ed., Sec. 14.2.4): a texel of an
// equirectangular environment chosen in proportion to its luminance times sin(theta) by two float32 CDFs,
// the rows' marginal (1 x (H + 1) texels) and each row's conditional (H x (W + 1)), then a uniform point
// inside it in (u, v), turned by `turn` (the env view's environment_turn). Its density in solid angle is
// p_texel W H / (2 pi^2 sin theta), p_texel read back from the same CDFs (their differences), so that the
// density the estimator divides by is the one the float32 CDFs sample. Twins: explorer/views/env.py
// (environment_sampling_tables, sample_environment, environment_pdf).

// The last index k in [0, count - 1) with cdf(k) <= x, by bisection (cdf(0) = 0, cdf(count - 1) = 1).
int cdf_search(sampler2D cdf, int row, int count, float x) {
    int lo = 0, hi = count - 1;
    while (hi - lo > 1) {
        int mid = (lo + hi) / 2;
        if (texelFetch(cdf, ivec2(mid, row), 0).r <= x) lo = mid; else hi = mid;
    }
    return lo;
}

vec3 environment_direction(float u, float v) {  // the inverse of the env view's (u, v) of a direction
    float phi = 2.0 * PI * (u - 0.5), theta = PI * v;
    return vec3(sin(theta) * sin(phi), cos(theta), -sin(theta) * cos(phi));
}

vec3 sample_environment(sampler2D marginal, sampler2D conditional, float turn, vec2 u) {
    int rows = textureSize(conditional, 0).y, columns = textureSize(conditional, 0).x - 1;
    int i = cdf_search(marginal, 0, rows + 1, u.x);
    float r0 = texelFetch(marginal, ivec2(i, 0), 0).r, r1 = texelFetch(marginal, ivec2(i + 1, 0), 0).r;
    float fv = clamp((u.x - r0) / max(r1 - r0, 1e-30), 0.0, 1.0);
    int j = cdf_search(conditional, i, columns + 1, u.y);
    float c0 = texelFetch(conditional, ivec2(j, i), 0).r, c1 = texelFetch(conditional, ivec2(j + 1, i), 0).r;
    float fu = clamp((u.y - c0) / max(c1 - c0, 1e-30), 0.0, 1.0);
    return environment_direction((float(j) + fu) / float(columns) + turn, (float(i) + fv) / float(rows));
}

float environment_pdf(sampler2D marginal, sampler2D conditional, float turn, vec3 d) {
    int rows = textureSize(conditional, 0).y, columns = textureSize(conditional, 0).x - 1;
    float sin_theta = length(d.xz);
    if (sin_theta <= 1e-7) return 0.0;
    float u = fract(0.5 + atan(d.x, -d.z) * (0.5 / PI) - turn);
    float v = atan(sin_theta, d.y) * (1.0 / PI);
    int i = clamp(int(v * float(rows)), 0, rows - 1), j = clamp(int(u * float(columns)), 0, columns - 1);
    float row_mass = texelFetch(marginal, ivec2(i + 1, 0), 0).r - texelFetch(marginal, ivec2(i, 0), 0).r;
    float column_mass = texelFetch(conditional, ivec2(j + 1, i), 0).r - texelFetch(conditional, ivec2(j, i), 0).r;
    return row_mass * column_mass * float(rows * columns) / (2.0 * PI * PI * sin_theta);
}
