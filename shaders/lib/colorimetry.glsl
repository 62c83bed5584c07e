// The colour convention (explorer/physics/colorimetry.py) and the CMF tables of luts/ (explorer/tables/luts.py).
// Tables are 2D textures of height 1 (moderngl has no 1D textures). The host binds: cmf_1nm (471 texels, CMFs at 360..830 nm, sum(ybar) = 1), cmf_cumulative (472 texels,
// their cumulative integral at the bin edges 359.5 + k nm, linear filtering, clamped to edge) and
// xyz_to_rgb_matrix (XYZ with E white -> linear sRGB with white (1, 1, 1)).

uniform sampler2D cmf_1nm;         // 471 x 1
uniform sampler2D cmf_cumulative;  // 472 x 1
uniform mat3 xyz_to_rgb_matrix;

#include "generated/colorimetry.glsl"  // the constants shared with explorer/physics (generated at assembly)

// CMFs at wavelength 360 + index nm.
vec3 colour_matching_functions(int index) { return texelFetch(cmf_1nm, ivec2(index, 0), 0).rgb; }

// The CMFs interpolated linearly between their 1 nm nodes, zero from 359 and 831 nm outwards: the hat
// functions the converged spectral integral weights a spectrum with.
vec3 colour_matching_functions_at(float wavelength) {
    float x = wavelength - CMF_FIRST_WAVELENGTH;
    float i = floor(x);
    int k = int(i);
    vec3 low = (k >= 0 && k < CMF_COUNT) ? colour_matching_functions(k) : vec3(0.0);
    vec3 high = (k + 1 >= 0 && k + 1 < CMF_COUNT) ? colour_matching_functions(k + 1) : vec3(0.0);
    return mix(low, high, x - i);
}

// C(lambda) (Eq. 16): node k sits at the centre of texel k.
vec3 cmf_cumulative_at(float wavelength) {
    return texture(cmf_cumulative, vec2((wavelength - CUMULATIVE_START + 0.5) / CUMULATIVE_SIZE, 0.5)).rgb;
}

vec3 xyz_to_rgb(vec3 xyz) { return xyz_to_rgb_matrix * xyz; }
