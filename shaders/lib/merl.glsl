// Measured isotropic BRDFs in the MERL format (Matusik et al. 2003): the half/difference angles, the
// table's bins and its nearest-bin lookup. Twin: explorer/physics/merl.py (same function names).
//
// The table merl_table holds f(theta_h, theta_d, phi_d), the channel scales (1/1500, 1.15/1500, 1.66/1500)
// applied by the host: texel (i_phi, i_h 90 + i_d), 180 x 8100 texels, read by texelFetch (no filtering,
// as MERL's BRDFRead.cpp). theta_h's bins are non-linear, i_h = floor(sqrt(theta_h / 90 deg) 90); a
// negative phi_d is shifted by pi (an isotropic BRDF's reciprocity). Angles from atan, not acos: the first
// theta_h bin ends at 0.011 deg, below what acos resolves near 1 in float32.

#define MERL_THETA_H_BINS 90
#define MERL_THETA_D_BINS 90
#define MERL_PHI_D_BINS 180
#define MERL_HALF_PI 1.57079632679489661923
#define MERL_PI 3.14159265358979323846

uniform sampler2D merl_table;

// (theta_h, theta_d, phi_d) of local L and V (normal +z): D is L rotated by -phi_h about z, then -theta_h about y.
vec3 merl_half_diff(vec3 L, vec3 V) {
    vec3 H = normalize(L + V);
    float theta_h = atan(length(H.xy), H.z);
    float phi_h = atan(H.y, H.x);
    float c = cos(phi_h), s = sin(phi_h);
    float tx = c * L.x + s * L.y;
    float ty = -s * L.x + c * L.y;
    float ch = cos(theta_h), sh = sin(theta_h);
    float dx = tx * ch - L.z * sh;
    float dz = tx * sh + L.z * ch;
    return vec3(theta_h, atan(length(vec2(dx, ty)), dz), atan(ty, dx));
}

// The bins (i_h, i_d, i_phi) of half/difference angles, each clamped to its range.
ivec3 merl_index(vec3 angles) {
    float degrees_h = max(angles.x, 0.0) / MERL_HALF_PI * float(MERL_THETA_H_BINS);
    int i_h = clamp(int(floor(sqrt(degrees_h * float(MERL_THETA_H_BINS)))), 0, MERL_THETA_H_BINS - 1);
    int i_d = clamp(int(floor(angles.y / MERL_HALF_PI * float(MERL_THETA_D_BINS))), 0, MERL_THETA_D_BINS - 1);
    float phi = angles.z < 0.0 ? angles.z + MERL_PI : angles.z;
    int i_phi = clamp(int(floor(phi / MERL_PI * float(MERL_PHI_D_BINS))), 0, MERL_PHI_D_BINS - 1);
    return ivec3(i_h, i_d, i_phi);
}

// The measured BRDF in the frame (X, Y, N): the nearest bin's linear RGB.
vec3 merl_brdf(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y) {
    vec3 l = vec3(dot(L, X), dot(L, Y), dot(L, N));
    vec3 v = vec3(dot(V, X), dot(V, Y), dot(V, N));
    ivec3 i = merl_index(merl_half_diff(l, v));
    return texelFetch(merl_table, ivec2(i.z, i.x * MERL_THETA_D_BINS + i.y), 0).rgb;
}
