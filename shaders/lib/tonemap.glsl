// Tone mapping of exposed linear RGB to linear display RGB in [0, 1], before the sRGB encode: the GLSL
// twin of explorer.views.tonemap (same names, same constants; the sources of the curves are cited there).
// TONEMAP_NONE clamps; TONEMAP_AGX is Sobotka's AgX in Wrensch's minimal fit (inset, log2 over
// [AGX_MIN_EV, AGX_MAX_EV], the contrast sigmoid's polynomial, outset, 2.2 EOTF); TONEMAP_ACES is
// Narkowicz's ACES fit of 0.6 x.
#ifndef TONEMAP_GLSL
#define TONEMAP_GLSL

#define TONEMAP_NONE 0
#define TONEMAP_AGX 1
#define TONEMAP_ACES 2

const float AGX_MIN_EV = -12.47393;
const float AGX_MAX_EV = 4.026069;
const float AGX_FLOOR = 1e-10;

vec3 agx(vec3 rgb) {
    const mat3 agx_inset = mat3(
        0.842479062253094, 0.0423282422610123, 0.0423756549057051,
        0.0784335999999992, 0.878468636469772, 0.0784336,
        0.0792237451477643, 0.0791661274605434, 0.879142973793104);
    const mat3 agx_outset = mat3(
        1.19687900512017, -0.0528968517574562, -0.0529716355144438,
        -0.0980208811401368, 1.15190312990417, -0.0980434501171241,
        -0.0990297440797205, -0.0989611768448433, 1.15107367264116);
    vec3 x = agx_inset * rgb;
    x = clamp(log2(max(x, vec3(AGX_FLOOR))), AGX_MIN_EV, AGX_MAX_EV);
    x = (x - AGX_MIN_EV) / (AGX_MAX_EV - AGX_MIN_EV);
    vec3 x2 = x * x;
    vec3 x4 = x2 * x2;
    x = 15.5 * x4 * x2 - 40.14 * x4 * x + 31.96 * x4 - 6.868 * x2 * x + 0.4298 * x2 + 0.1191 * x - 0.00232;
    x = agx_outset * x;
    return pow(clamp(x, 0.0, 1.0), vec3(2.2));
}

vec3 aces(vec3 rgb) {
    vec3 x = max(rgb * 0.6, vec3(0.0));
    return clamp(x * (2.51 * x + 0.03) / (x * (2.43 * x + 0.59) + 0.14), 0.0, 1.0);
}

vec3 tonemap(vec3 rgb, int curve) {
    if (curve == TONEMAP_AGX) return agx(rgb);
    if (curve == TONEMAP_ACES) return aces(rgb);
    return clamp(rgb, 0.0, 1.0);
}

#endif
