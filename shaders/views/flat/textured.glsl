// The textured view flat (render --maps DIR --theta DEG --engine gl): one pixel a texel of the surface texture, each
// texel's colour at the viewing angle flat_cos_theta: the material's surface_reflectance(cos_theta, value) (its
// textured_reflectance for that texel's value; structure maps: its own structure). No light, no sphere.
// Twin: explorer.views.maps.flat_numpy (the twin's surface_reflectance).
#include "lib/views.glsl"

uniform vec2 resolution;
uniform float flat_cos_theta;
out vec4 frag_colour;

void main() {
    ivec2 size = textureSize(surface_texture, 0);
    ivec2 texel = ivec2(int(gl_FragCoord.x), size.y - 1 - int(gl_FragCoord.y));  // rows from the top
    frag_colour = vec4(finite_or_zero(surface_reflectance(flat_cos_theta, texelFetch(surface_texture, texel, 0).r)), 1.0);
}
