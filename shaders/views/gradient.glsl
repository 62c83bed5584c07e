// The gradient view: column i shows the mirror's reflectance at theta = 90 deg (i + 0.5) / W, every row
// the same (the colour strips of Figure 4). Twin: explorer.views.geometry.view_cos_theta('gradient', ...).
uniform vec2 resolution;
out vec4 frag_colour;

void main() {
    float theta = radians(90.0) * gl_FragCoord.x / resolution.x;  // gl_FragCoord.x = i + 0.5
    frag_colour = vec4(reflectance(cos(theta)), 1.0);
}
