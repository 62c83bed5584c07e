// What the disc views share (sphere, lit, scatter, textured; twins in explorer/render.py).

// Pixel (i, j), j from the top, at p = (2 (i + 0.5) / W - 1, 1 - 2 (j + 0.5) / H); false outside the unit disc.
bool disc_point(vec2 resolution, out vec2 p, out float r2) {
    p = 2.0 * gl_FragCoord.xy / resolution - 1.0;  // gl_FragCoord.y counts from the bottom
    r2 = dot(p, p);
    return r2 < 1.0;
}

// BRDF Explorer's lit-sphere frame (src/shaderTemplates/brdftemplatesphere.frag) at a point of the
// orthographic unit sphere: N = (x, y, sqrt(1 - r^2)), X = normalize(cross((0, 1, 0), N)),
// Y = normalize(cross(N, X)).
void lit_sphere_frame(vec2 p, float r2, out vec3 normal, out vec3 tangent, out vec3 bitangent) {
    normal = vec3(p, sqrt(1.0 - r2));
    tangent = normalize(cross(vec3(0.0, 1.0, 0.0), normal));
    bitangent = normalize(cross(normal, tangent));
}
