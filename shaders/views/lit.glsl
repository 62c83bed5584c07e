// The lit view: the orthographic unit sphere of the sphere view, seen along V = (0, 0, 1) and lit by one
// directional light of unit irradiance from light_direction (unit, toward the light). Pixel (i, j), j from
// the top, lies at x = 2 (i + 0.5) / W - 1, y = 1 - 2 (j + 0.5) / H; inside the disc the normal is
// N = (x, y, sqrt(1 - x^2 - y^2)) and the pixel is view_brdf(L, V, N, X, Y) max(0, N.L) (lib/views.glsl: 0
// unless N.L > 0 and N.V > 0, non-finite channels 0), outside 0. The frame is
// BRDF Explorer's lit sphere (src/shaderTemplates/brdftemplatesphere.frag): X = normalize(cross((0, 1, 0),
// N)), Y = normalize(cross(N, X)). Twin: explorer.views.render.render_numpy(model, 'lit', ...).
//
// A smooth mirror (a material that declares MIRROR_ONLY and its Dirac weight mirror_reflection(V, N), the env
// view's hooks, views/env.glsl) is black under one directional light but at one point: it shows instead what
// it shows under the env view, mirror_reflection(V, N) Le(reflect(-V, N)) from mirror_environment (the env
// view's environment by default, turned by mirror_environment_turn), plus the light as a small glint of unit
// irradiance (light_glint: a disc of angular radius rho, sin^2 rho = glint_sin2; both uniforms from the host).
// Twin: explorer.views.mirror.mirror_lit.
//
// Any other material adds the environment fill (explorer.views.fill): a uniform white environment of radiance
// `fill` sends fill a(theta_v) toward the eye, a the directional albedo, from the host's table fill_albedo at
// theta_k = 90 (k + 0.5) / FILL_ANGLES degrees, linear in theta between them and clamped at the ends. fill = 0:
// the point light alone. Twin: explorer.views.fill.fill_radiance.
#include "lib/views.glsl"
#if defined(MIRROR_ONLY) && defined(HAS_MIRROR_REFLECTION)
#define LIT_MIRROR
#include "lib/environment.glsl"
uniform sampler2D mirror_environment;
uniform float mirror_environment_turn;
uniform float glint_sin2;
uniform float glint_peak;

// The light seen in the mirror: glint_peak t^3, t = 1 - |r x l|^2 / sin^2 rho, within rho of the light (its
// irradiance facing the light is pi sin^2 rho / 4 glint_peak = 1). In sin^2 (a cross product): float32 keeps
// its digits near the light, where 1 - cos would not.
float light_glint(vec3 r, vec3 l) {
    vec3 c = cross(r, l);
    float t = 1.0 - dot(c, c) / glint_sin2;
    return dot(r, l) > 0.0 && t > 0.0 ? glint_peak * t * t * t : 0.0;
}
#endif

uniform vec2 resolution;
uniform vec3 light_direction;
out vec4 frag_colour;

#ifndef LIT_MIRROR
#define FILL_ANGLES 16
uniform float fill;
uniform vec3 fill_albedo[FILL_ANGLES];

vec3 fill_radiance(float cos_view) {
    float t = clamp(degrees(acos(clamp(cos_view, 0.0, 1.0))) / 90.0 * float(FILL_ANGLES) - 0.5, 0.0, float(FILL_ANGLES - 1));
    int k = int(floor(t));
    int k1 = min(k + 1, FILL_ANGLES - 1);
    return fill * mix(fill_albedo[k], fill_albedo[k1], t - float(k));
}
#endif

void main() {
    vec3 normal, tangent, bitangent;
    if (!view_surface(resolution, normal, tangent, bitangent)) {  // the sphere, or a mesh (views/mesh/lit.glsl)
        frag_colour = vec4(0.0, 0.0, 0.0, 1.0);
        return;
    }
    vec3 view = vec3(0.0, 0.0, 1.0);
#ifdef LIT_MIRROR
    vec3 reflected = reflect(-view, normal);
    vec3 incoming = environment_radiance(mirror_environment, mirror_environment_turn, reflected)
                  + light_glint(reflected, light_direction);
    vec3 radiance = finite_or_zero(mirror_reflection(view, normal)) * incoming;
#else
    vec3 radiance = view_brdf(light_direction, view, normal, tangent, bitangent) * max(0.0, dot(normal, light_direction));
    if (fill > 0.0) radiance += fill_radiance(dot(normal, view));
#endif
    frag_colour = vec4(radiance, 1.0);
}
