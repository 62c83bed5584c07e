// The lit view: the orthographic unit sphere of the sphere view, seen along V = (0, 0, 1) and lit by one
// directional light of unit irradiance from light_direction (unit, toward the light). Pixel (i, j), j from
// the top, lies at x = 2 (i + 0.5) / W - 1, y = 1 - 2 (j + 0.5) / H; inside the disc the normal is
// N = (x, y, sqrt(1 - x^2 - y^2)) and the pixel is view_brdf(L, V, N, X, Y) max(0, N.L) (lib/views.glsl: 0
// unless N.L > 0 and N.V > 0, non-finite channels 0), outside 0. The frame is
// BRDF Explorer's lit sphere (src/shaderTemplates/brdftemplatesphere.frag): X = normalize(cross((0, 1, 0),
// N)), Y = normalize(cross(N, X)). Twin: explorer.views.render.render_numpy(model, 'lit', ...).
#include "lib/views.glsl"

uniform vec2 resolution;
uniform vec3 light_direction;
out vec4 frag_colour;

void main() {
    vec3 normal, tangent, bitangent;
    if (!view_surface(resolution, normal, tangent, bitangent)) {  // the sphere, or a mesh (views/mesh/lit.glsl)
        frag_colour = vec4(0.0, 0.0, 0.0, 1.0);
        return;
    }
    vec3 view = vec3(0.0, 0.0, 1.0);
    vec3 radiance = view_brdf(light_direction, view, normal, tangent, bitangent) * max(0.0, dot(normal, light_direction));
    frag_colour = vec4(radiance, 1.0);
}
