// What the views share (sphere, lit, scatter, textured, env, slice; twins in explorer/views/render.py and explorer/views/geometry.py). Included
// after the material's source: view_brdf calls its BRDF.

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

// The surface a pixel of the lit and env views shows, and its frame: the sphere's (above), or with
// MESH_NORMALS a mesh's interpolated normal from a rasterising pass (explorer/gpu/mesh.py; w = 1 where the
// mesh covers the pixel) in the same frame, X = (1, 0, 0) where cross((0, 1, 0), N) vanishes. False off
// the surface. Twins: explorer/views/geometry.py (brdf_view_geometry), explorer/views/mesh.py (surface_frame).
#ifdef MESH_NORMALS
uniform sampler2D mesh_normals;
// The interpolated texture coordinates (u, v, 0, 1) of the same pass (zeros for a mesh without them).
uniform sampler2D mesh_uvs;
bool view_surface(vec2 resolution, out vec3 normal, out vec3 tangent, out vec3 bitangent) {
    // The texel under the pixel: the same size (a headless render), or the app's preview at a smaller one.
    vec4 surface = texelFetch(mesh_normals, ivec2(gl_FragCoord.xy * vec2(textureSize(mesh_normals, 0)) / resolution), 0);
    if (surface.w <= 0.0) return false;
    normal = normalize(surface.xyz);
    vec3 across = cross(vec3(0.0, 1.0, 0.0), normal);
    tangent = length(across) > 1e-6 ? normalize(across) : vec3(1.0, 0.0, 0.0);
    bitangent = normalize(cross(normal, tangent));
    return true;
}
#else
bool view_surface(vec2 resolution, out vec3 normal, out vec3 tangent, out vec3 bitangent) {
    vec2 p;
    float r2;
    if (!disc_point(resolution, p, r2)) return false;
    lit_sphere_frame(p, r2, normal, tangent, bitangent);
    return true;
}
#endif

// The rule of every view that evaluates a material's BRDF (lit, slice, scatter, textured, env; the numpy
// twins in explorer/views/geometry.py have the same names): the BRDF is evaluated only where the light and the
// view are both strictly above the surface, N.L > 0 and N.V > 0, and is 0 elsewhere (BRDF Explorer's lit
// sphere evaluates it everywhere and relies on max(BRDF, 0) and the cosine, but Minnaert's or Ward's
// pow(N.L N.V, e) and sqrt(N.L N.V) are NaN below the horizon and NaN * 0 stays NaN). A channel the
// material returns as NaN or +-infinity counts as 0 (edwards06's pow(1 - |h|^2 / R^2, n) is NaN on the lit
// side too): GLSL leaves operations on NaN undefined, max(NaN, 0) included, so the test is explicit. A
// finite negative channel is kept: linear sRGB of a vivid spectrum is negative outside the gamut.

bool above_surface(vec3 L, vec3 V, vec3 N) {
    return dot(N, L) > 0.0 && dot(N, V) > 0.0;
}

float finite_or_zero(float x) { return isnan(x) || isinf(x) ? 0.0 : x; }
vec3 finite_or_zero(vec3 f) { return vec3(finite_or_zero(f.x), finite_or_zero(f.y), finite_or_zero(f.z)); }

// The material's BRDF(L, V, N, X, Y) under the rule above.
vec3 view_brdf(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y) {
    return above_surface(L, V, N) ? finite_or_zero(BRDF(L, V, N, X, Y)) : vec3(0.0);
}

// -- BRDF Explorer's plots (shaders/views/{theta_v,theta_h,theta_d,lobe3d,albedo}.glsl; twins in explorer/views/plots.py)

// Column i's angle (radians) of a plot over [first, first + span]: first + span (i + 0.5) / W.
float plot_column_angle(float first, float span, float width) {
    return first + span * gl_FragCoord.x / width;
}

vec3 unit_direction(float theta, float phi) {
    return vec3(sin(theta) * cos(phi), sin(theta) * sin(phi), cos(theta));
}

// L and V of half-vector angle theta_h (phi_h = 0) and difference angles theta_d, phi_d (Rusinkiewicz
// 1998): D rotated by theta_h about Y, V the reflection of L about H (the slice view's construction).
void rusinkiewicz_directions(float theta_h, float theta_d, float phi_d, out vec3 L, out vec3 V) {
    vec3 H = unit_direction(theta_h, 0.0);
    vec3 D = unit_direction(theta_d, phi_d);
    float c = cos(theta_h), s = sin(theta_h);
    L = vec3(D.x * c + D.z * s, D.y, -D.x * s + D.z * c);
    V = 2.0 * dot(H, L) * H - L;
}

// -- The surface texture (textured and env views; the host #defines SURFACE_TEXTURE): what a material's
// '# texture:' varies (explorer/views/surface_texture.py). Planar parametrisation of the disc point p:
// u = (x + 1) / 2, v = (1 - y) / 2 (rows from the top), bilinear between texel centres, clamped (or the nearest texel).
#ifdef SURFACE_TEXTURE
uniform sampler2D surface_texture;

float surface_bilinear(vec2 uv) {
    ivec2 size = textureSize(surface_texture, 0);
    vec2 t = clamp(uv * vec2(size) - 0.5, vec2(0.0), vec2(size - 1));
    ivec2 i = min(ivec2(floor(t)), max(size - 2, ivec2(0)));
    vec2 f = t - vec2(i);
    ivec2 i1 = min(i + 1, size - 1);
    float top = mix(texelFetch(surface_texture, i, 0).r, texelFetch(surface_texture, ivec2(i1.x, i.y), 0).r, f.x);
    float bottom = mix(texelFetch(surface_texture, ivec2(i.x, i1.y), 0).r, texelFetch(surface_texture, i1, 0).r, f.x);
    return mix(top, bottom, f.y);
}

// surface_nearest: the nearest texel's value, unfiltered (structure maps: a texel index, never blended).
uniform bool surface_nearest;

float surface_at(vec2 uv) {
    if (surface_nearest) {
        ivec2 size = textureSize(surface_texture, 0);
        return texelFetch(surface_texture, clamp(ivec2(floor(uv * vec2(size))), ivec2(0), size - 1), 0).r;
    }
    return surface_bilinear(uv);
}

// The texture coordinates of the fragment: the sphere's planar ones of its disc point, or a mesh's interpolated ones
// (explorer/gpu/mesh.py; twin: explorer.views.mesh.rasterise's uvs). Its surface value: surface_at(surface_uv(...)).
vec2 surface_uv(vec2 resolution) {
#ifdef MESH_NORMALS
    return texelFetch(mesh_uvs, ivec2(gl_FragCoord.xy * vec2(textureSize(mesh_uvs, 0)) / resolution), 0).xy;
#else
    vec2 p;
    float r2;
    disc_point(resolution, p, r2);
    return vec2(0.5 * (p.x + 1.0), 0.5 * (1.0 - p.y));
#endif
}
#endif
