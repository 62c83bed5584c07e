// The sphere view: an orthographic unit sphere in a uniform white environment. Pixel (i, j), j from the
// top, lies at x = 2 (i + 0.5) / W - 1, y = 1 - 2 (j + 0.5) / H; inside the disc it shows the mirror's
// reflectance at cos theta = sqrt(1 - x^2 - y^2), outside 0. Twin: explorer.views.geometry.view_cos_theta.
#include "lib/views.glsl"

uniform vec2 resolution;
out vec4 frag_colour;

void main() {
    vec2 p;
    float r2;
    frag_colour = disc_point(resolution, p, r2) ? vec4(reflectance(sqrt(1.0 - r2)), 1.0) : vec4(0.0, 0.0, 0.0, 1.0);
}
