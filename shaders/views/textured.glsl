// The textured view: the lit view's sphere (same pixels, light, N, X, Y; explorer.views.render) with a material
// parameter that varies over it, as the material declares ('# texture:', explorer/views/surface_texture.py): a
// thin film's D_inc (Belcour & Barla 2017, Section 5, Figures 12-15; surface_texture holds D_inc in nm) or a Bragg
// mirror's Lambda and delta (supplemental Figure 7; surface_texture holds T in [0, 1]). The material defines
// textured_BRDF(L, V, N, X, Y, value, sigma_value, prefiltered) (shaders/thin_film.brd, shaders/bragg_mirror.brd).
// Planar parametrisation (explorer/views/thickness.py): pixel p = (x, y) reads surface_texture at
// u = (x + 1) / 2, v = (1 - y) / 2 (rows from the top), bilinearly between texel centres, clamped.
// prefilter (the film only): the value's mean and variance over the pixel's footprint come from surface_moments
// (computed by the host, one texel per pixel, rows from the top) and the material averages Eq. 10 over that Gaussian.
// The rule of lib/views.glsl's view_brdf applies: 0 unless N.L > 0 and N.V > 0, non-finite channels 0.
// On a mesh (views/mesh/textured.glsl, MESH_NORMALS): its normals and its texture coordinates instead (no prefiltering).
// Twin: explorer.views.render.render_numpy(model, 'textured', ..., thickness=..., mesh=...).
#include "lib/views.glsl"

uniform vec2 resolution;
uniform vec3 light_direction;
uniform sampler2D surface_moments;
uniform bool prefilter;
out vec4 frag_colour;

void main() {
    vec3 normal, tangent, bitangent;
    if (!view_surface(resolution, normal, tangent, bitangent)) {  // the sphere, or a mesh
        frag_colour = vec4(0.0, 0.0, 0.0, 1.0);
        return;
    }
    vec3 view = vec3(0.0, 0.0, 1.0);
    float D_inc_, sigma = 0.0;
    if (prefilter) {
        ivec2 pixel = ivec2(int(gl_FragCoord.x), int(resolution.y) - 1 - int(gl_FragCoord.y));
        vec2 moments = texelFetch(surface_moments, pixel, 0).rg;
        D_inc_ = moments.x;
        sigma = sqrt(max(moments.y, 0.0));
    } else {
        D_inc_ = surface_at(surface_uv(resolution));
    }
    vec3 f = above_surface(light_direction, view, normal)
        ? finite_or_zero(textured_BRDF(light_direction, view, normal, tangent, bitangent, D_inc_, sigma, prefilter))
        : vec3(0.0);
    vec3 radiance = f * max(0.0, dot(normal, light_direction));
    frag_colour = vec4(radiance, 1.0);
}
