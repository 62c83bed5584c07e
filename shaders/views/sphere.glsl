// The sphere view: an orthographic unit sphere in a uniform white environment. Pixel (i, j), j from the
// top, lies at x = 2 (i + 0.5) / W - 1, y = 1 - 2 (j + 0.5) / H; inside the disc it shows the mirror's
// reflectance at cos theta = sqrt(1 - x^2 - y^2), outside 0. Twin: explorer.render.view_cos_theta.
uniform vec2 resolution;
out vec4 frag_colour;

void main() {
    vec2 p = 2.0 * gl_FragCoord.xy / resolution - 1.0;  // gl_FragCoord.y counts from the bottom
    float r2 = dot(p, p);
    frag_colour = r2 < 1.0 ? vec4(reflectance(sqrt(1.0 - r2)), 1.0) : vec4(0.0, 0.0, 0.0, 1.0);
}
