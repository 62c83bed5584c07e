// The env view: the lit view's orthographic unit sphere (V = (0, 0, 1), N and BRDF Explorer's frame X, Y
// from lib/views.glsl) under an environment map, by progressive Monte Carlo. Each pass adds
// samples_per_pass samples per pixel of the estimator f(L, V) cos theta_L Le(L) / pdf(L); the host blends
// the passes additively (explorer/gpu/env.py, ProgressiveEnvRender) and divides by the sample count.
//
// Random numbers: the PCG4D hash of (pixel, sample index, seed), the sample index counted from the first
// sample of the render (first_sample + s): the same numbers however the host splits the samples into passes.
//
// Outputs: sum_out = (sum of the samples, count), square_out = (sum of their squares, samples where the
// material's BRDF was NaN or infinite, counted as 0 by view_brdf's rule in lib/views.glsl); both float32,
// added over passes.
//
// Sampling (one-sample MIS, balance heuristic): without the material hook, cosine sampling about N. With
//   #define HAS_SAMPLING_LOBES
//   float sampling_lobes(vec3 V, vec3 N, out vec4 alphas, out vec4 weights);
// (up to four GGX lobes of roughness alphas[k] and weights[k] >= 0, returning the weight of a cosine lobe,
// unnormalised) a lobe is chosen with probability w / sum(w), sampled (GGX: Heitz 2018's visible normals
// reflected about V; the cosine lobe: Malley's method) and the sample divided by the mixture density
// sum_k w_k pdf_k(L) + w_c cos theta_L / pi. Unbiased for any weights; the weights only change the variance.
//
// A Dirac reflection (a smooth coating, Eq. 34's f_r,0) cannot be sampled by directions; a material declares it
//   #define HAS_MIRROR_REFLECTION
//   vec3 mirror_reflection(vec3 V, vec3 N);  // its weight into reflect(-V, N)
// and every sample adds mirror_reflection(V, N) Le(reflect(-V, N)) exactly (no variance). A material that is
// nothing but that Dirac (a smooth mirror) also declares
//   #define MIRROR_ONLY
// and its BRDF (what the slice view shows) is not sampled.
//
// Environment sampling (lib/sampling.glsl's sample_environment): with probability w a sample is drawn from
// the environment's luminance (its CDFs environment_marginal, environment_conditional), else from the
// material's mixture above; the density divided by is the whole mixture's,
// (1 - w) (sum_k w_k pdf_k + w_c cos / pi) + w pdf_env (one-sample MIS, balance heuristic; Veach 1997, 9.2).
// The share w is the pixel's (environment_share): the lobes' shares weighted as the lobes are chosen, a lobe's
// w_max x / (1 + x) with x = environment_share_scale Omega, Omega its solid angle (4 pi alpha^2 for GGX, at
// most 2 pi; 2 pi for the cosine lobe) and environment_share_scale = 3 / the environment's effective solid
// angle (explorer.views.env.environment_share, its twin): a lobe narrower than the environment's bright
// parts takes mostly its own samples, a broad one mostly the environment's. Constant over a pixel's
// samples, so the estimator stays unbiased; a negative scale fixes w = w_max (environment_sampling_weight).
//
// Environment: equirectangular, linear RGB, looked up as lib/environment.glsl describes (its convention,
// linear filtering, repeat in u, clamp in v). Twin: explorer.views.env.EnvironmentMap.
#include "lib/views.glsl"
#include "lib/sampling.glsl"
#include "lib/environment.glsl"

uniform vec2 resolution;
uniform sampler2D environment;
// The probe's turn about the vertical +y (a fraction of a turn: u shifts by it; explorer.views.env.EnvironmentMap.rotation).
uniform float environment_turn;
// Off the object: the environment behind it (a pinhole's view along -z, BACKDROP_TAN the tangent of its
// half field; twin: explorer.views.env.backdrop), else black.
uniform bool show_background;
uniform float environment_sampling_weight;  // w_max, the largest share; 0: the material's sampling only
uniform float environment_share_scale;  // 1 / sr; negative: the share is w_max everywhere
uniform sampler2D environment_marginal;
uniform sampler2D environment_conditional;
#define BACKDROP_TAN 0.57735026918962576
uniform uint first_sample;
uniform int samples_per_pass;
uniform uint seed;
#ifdef HAS_TEXTURED_BRDF
// A material that declares '# texture:' under its surface texture (explorer/views/surface_texture.py): its
// textured_BRDF (and a mirror's textured_mirror_reflection) at the pixel's texture value.
uniform bool textured;
#endif
layout(location = 0) out vec4 sum_out;
layout(location = 1) out vec4 square_out;

vec3 environment_radiance(vec3 d) { return environment_radiance(environment, environment_turn, d); }

// x > 0, false for NaN (GLSL's max() is undefined for NaN).
float positive_or_zero(float x) { return x > 0.0 ? x : 0.0; }

// The share of environment samples for a lobe of solid angle omega (sr): w_max x / (1 + x), x = scale omega.
float lobe_environment_share(float omega) {
    float x = environment_share_scale * omega;
    return environment_sampling_weight * x / (1.0 + x);
}

// The pixel's share: the lobes' (GGX: omega = min(4 pi alpha^2, 2 pi); the cosine lobe: 2 pi) by their weights.
float environment_share(vec4 alphas, vec4 weights, float cosine_weight) {
    if (environment_share_scale < 0.0) return environment_sampling_weight;
    float share = cosine_weight * lobe_environment_share(2.0 * PI);
    for (int j = 0; j < 4; ++j) {
        if (weights[j] > 0.0) share += weights[j] * lobe_environment_share(min(4.0 * PI * alphas[j] * alphas[j], 2.0 * PI));
    }
    return share;
}

void main() {
    vec3 normal, tangent, bitangent;
    if (!view_surface(resolution, normal, tangent, bitangent)) {  // the sphere, or a mesh (views/mesh/env.glsl)
        vec3 behind = vec3(0.0);
        if (show_background) {
            vec2 p = (2.0 * gl_FragCoord.xy - resolution) / min(resolution.x, resolution.y);
            behind = environment_radiance(normalize(vec3(p * BACKDROP_TAN, -1.0)));
        }
        float n = float(samples_per_pass);
        sum_out = vec4(behind * n, n);  // exact: no variance
        square_out = vec4(behind * behind * n, 0.0);
        return;
    }
    vec3 view = vec3(0.0, 0.0, 1.0);
    vec3 t, b;
    sampling_basis(normal, t, b);
    vec3 view_local = vec3(dot(view, t), dot(view, b), dot(view, normal));

    vec4 alphas = vec4(0.0), weights = vec4(0.0);
    float cosine_weight = 1.0;
#ifdef HAS_SAMPLING_LOBES
    cosine_weight = positive_or_zero(sampling_lobes(view, normal, alphas, weights));
    weights = vec4(positive_or_zero(weights.x), positive_or_zero(weights.y), positive_or_zero(weights.z),
                   positive_or_zero(weights.w));
    float total = cosine_weight + weights.x + weights.y + weights.z + weights.w;
    if (total > 0.0 && !isinf(total)) {
        weights /= total;
        cosine_weight /= total;
    } else {  // a hook that returns nothing usable: cosine sampling
        weights = vec4(0.0);
        cosine_weight = 1.0;
    }
#endif

    bool use_texture = false;
    float surface = 0.0;
#ifdef HAS_TEXTURED_BRDF
    use_texture = textured;
    if (use_texture) surface = surface_at(surface_uv(resolution));  // as the textured view reads it (sphere or mesh)
#endif
    vec3 mirror = vec3(0.0);
#ifdef HAS_MIRROR_REFLECTION
#ifdef HAS_TEXTURED_MIRROR
    vec3 mirror_weight = use_texture ? textured_mirror_reflection(view, normal, surface) : mirror_reflection(view, normal);
#else
    vec3 mirror_weight = mirror_reflection(view, normal);
#endif
    mirror = mirror_weight * environment_radiance(reflect(-view, normal));
#endif
    uvec2 pixel = uvec2(gl_FragCoord.xy);
    float env_weight = environment_share(alphas, weights, cosine_weight);  // the same for every sample of the pixel
    vec3 sum = vec3(0.0), square = vec3(0.0);
    float dropped = 0.0;
    for (int s = 0; s < samples_per_pass; ++s) {
        vec4 u = uniform_floats(pcg4d(uvec4(pixel, first_sample + uint(s), seed)));
        vec3 light;
        float choice = (u.x - env_weight) / (1.0 - env_weight) - cosine_weight;  // u.x past the environment's share
        if (u.x < env_weight) {
            light = sample_environment(environment_marginal, environment_conditional, environment_turn, u.yz);
        } else if (choice < 0.0) {
            vec3 l = sample_cosine_hemisphere(u.yz);
            light = l.x * t + l.y * b + l.z * normal;
        } else {
            int k = 0;  // the lobe whose cumulative weight passes u.x (the last non-empty one on round-off)
            for (int j = 0; j < 4; ++j) {
                if (weights[j] > 0.0) {
                    k = j;
                    if (choice < weights[j]) break;
                    choice -= weights[j];
                }
            }
            vec3 m = sample_ggx_visible_normal(view_local, alphas[k], u.yz);
            vec3 micro = m.x * t + m.y * b + m.z * normal;
            light = 2.0 * dot(view, micro) * micro - view;
        }
        float cos_light = dot(normal, light);
        vec3 value = vec3(0.0);
#ifdef MIRROR_ONLY
        cos_light = 0.0;
#endif
        if (cos_light > 0.0) {
            float pdf = cosine_weight * cos_light * (1.0 / PI);
            for (int j = 0; j < 4; ++j) {
                if (weights[j] > 0.0) pdf += weights[j] * ggx_reflection_pdf(light, view, normal, alphas[j]);
            }
            if (env_weight > 0.0) {
                pdf = (1.0 - env_weight) * pdf
                    + env_weight * environment_pdf(environment_marginal, environment_conditional, environment_turn, light);
            }
            if (pdf > 0.0 && above_surface(light, view, normal)) {
                // lib/views.glsl's rule (view_brdf), the non-finite channels counted so the host can report them.
#ifdef HAS_TEXTURED_BRDF
                vec3 f = use_texture ? textured_BRDF(light, view, normal, tangent, bitangent, surface, 0.0, false)
                                     : BRDF(light, view, normal, tangent, bitangent);
#else
                vec3 f = BRDF(light, view, normal, tangent, bitangent);
#endif
                if (any(isnan(f)) || any(isinf(f))) dropped += 1.0;
                value = finite_or_zero(f) * (cos_light / pdf) * environment_radiance(light);
            }
        }
        value += mirror;
        // Any other non-finite sample would spoil the pixel for good: it is dropped and counted too.
        if (any(isnan(value)) || any(isinf(value))) {
            value = vec3(0.0);
            dropped += 1.0;
        }
        sum += value;
        square += value * value;
    }
    sum_out = vec4(sum, float(samples_per_pass));
    square_out = vec4(square, dropped);
}
