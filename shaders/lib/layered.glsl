// Layered Bragg structures: twin of explorer/physics/layered.py (Fourneau et al. 2024, Sections 4.2-4.3).
// Per-layer tables come from the host, one layer per channel (r, g, b = layers 1, 2, 3; zeros unused):
// rows theta = k THETA_STEP (k = 0..360, in the host medium), columns lambda = 360 + j nm (j = 0..470).
// They are read with texelFetch and interpolated here in float32, as explorer.physics.layered.lookup does:
// a linearly filtered fetch would blend neighbouring wavelengths and round its weights to 8 bits.
#include "lib/microfacet.glsl"
#include "lib/fresnel.glsl"
#include "lib/colorimetry.glsl"
#include "lib/multiscatter.glsl"

#include "generated/layered.glsl"  // the constants shared with explorer/physics (generated at assembly)

// The polar angle of a direction above the surface, by atan2 (precise near 0, unlike acos).
float polar_angle(vec3 v) { return atan(length(v.xy), max(v.z, 0.0)); }

// Row k and weight f of angle theta in the 0.25 degree tables, clamped to [0, 90] degrees.
void table_row(float theta, out int k, out float f) {
    float x = clamp(theta, 0.0, 0.5 * PI) / THETA_STEP;
    k = min(int(floor(x)), THETA_ROWS - 2);
    f = x - float(k);
}

vec3 table_fetch(sampler2D table, int wavelength_index, int k, float f) {
    return mix(texelFetch(table, ivec2(wavelength_index, k), 0).rgb, texelFetch(table, ivec2(wavelength_index, k + 1), 0).rgb, f);
}

// Snell's law through the smooth coating, from air into the host nh: same azimuth, sin' = sin / nh.
vec3 refract_into_host(vec3 direction, float nh) {
    vec2 tangent = direction.xy / nh;
    return vec3(tangent, sqrt(max(1.0 - dot(tangent, tangent), 0.0)));
}

// The coating's Fresnel reflectance from air into nh (Eq. 34's f_r,0 weight; 0 for nh = 1).
float coating_reflectance(float cos_theta_i, float nh) {
    return fresnel_reflectance(clamp(cos_theta_i, LAYER_COS_THETA_MIN, 1.0), 1.0, nh);
}

// 1 for the layers in use, 0 beyond.
vec3 layer_mask(int layer_count) { return vec3(1.0, layer_count >= 2 ? 1.0 : 0.0, layer_count >= 3 ? 1.0 : 0.0); }

// The single-reflection BRDF (Eq. 34) in linear sRGB, from the host's tables. i, o: unit directions in
// air in the local frame (n = +z). Each wavelength's paths through the layers are multiplied before the
// CMF integration; the base's RGB albedo multiplies the RGB of its spectral term (it has no spectrum).
// The host's absorption: one crossing of a gap of optical depth tau_h at cos theta in the host (Beer-Lambert).
float gap_transmittance(float tau_h, float cos_theta_host) {
    return tau_h == 0.0 ? 1.0 : exp(-tau_h / max(cos_theta_host, 1e-6));
}

// The host's index at wavelength j (host_table: 471 x 1, channel r; BraggStackModel's stack_host).
float host_index_at(sampler2D host_table, int j) { return texelFetch(host_table, ivec2(j, 0), 0).r; }

// Eq. 34's per-direction factors in a host of index nh: the coating's weight (1 - F)(1 - F) / nh^2 times the
// gaps above the first layer, each layer's Eq. 17 lobe, one gap crossed down and up, and the table rows of
// theta_i', theta_o', theta_d in the host. Once per pixel, or once per wavelength where a coated host disperses.
struct HostPaths {
    float path, gap;
    vec3 lobe;
    int k_i, k_o, k_d;
    float f_i, f_o, f_d;
};

HostPaths host_paths(vec3 i, vec3 o, float nh, bool coating, vec3 used, vec3 alphas, float tau_h) {
    HostPaths p;
    p.path = 1.0;
    vec3 ih = i, oh = o;
    if (coating) {
        // f_t,0 = 1 - F at the angles in air; directions refracted; radiance scaled by 1 / nh^2.
        p.path = (1.0 - coating_reflectance(i.z, nh)) * (1.0 - coating_reflectance(o.z, nh)) / (nh * nh);
        ih = refract_into_host(i, nh);
        oh = refract_into_host(o, nh);
    }
    // Eq. 17 per layer: D(h) G1(i) G1(o) / (4 cos_i cos_o), G1 / cos finite at grazing angles.
    vec3 h = normalize(ih + oh);
    p.lobe = vec3(0.0);
    for (int l = 0; l < MAX_LAYERS; ++l) {
        p.lobe[l] = used[l] * 0.25 * ggx_D(h.z, alphas[l]) * smith_G1_over_cos(max(ih.z, 0.0), alphas[l])
                  * smith_G1_over_cos(max(oh.z, 0.0), alphas[l]);
    }
    // Each gap above a layer, and above the base, crossed down along i' and up along o' (tau_h).
    p.gap = gap_transmittance(tau_h, max(ih.z, 0.0)) * gap_transmittance(tau_h, max(oh.z, 0.0));
    p.path *= p.gap;
    table_row(polar_angle(ih), p.k_i, p.f_i);
    table_row(polar_angle(oh), p.k_o, p.f_o);
    table_row(atan(length(ih - oh), length(ih + oh)), p.k_d, p.f_d);  // theta_d = angle(i, h)
    return p;
}

// Wavelength j's share of Eq. 34 with the per-direction factors p, added to the layers' and the base's XYZ.
void add_wavelength(int j, HostPaths p, vec3 used, sampler2D reflectance_table, sampler2D transmissivity_table,
                    inout vec3 xyz_layers, inout vec3 xyz_base) {
    vec3 R = table_fetch(reflectance_table, j, p.k_d, p.f_d);
    vec3 t = mix(vec3(1.0), table_fetch(transmissivity_table, j, p.k_i, p.f_i) * table_fetch(transmissivity_table, j, p.k_o, p.f_o), used);
    // The paths down to layers 2 and 3 and to the base (a layer beyond layer_count passes 1 and no gap).
    vec3 g = mix(vec3(1.0), vec3(p.gap), used);
    float p2 = p.path * t.x * g.y, p3 = p2 * t.y * g.z;
    float layers_term = p.lobe.x * R.x * p.path + p.lobe.y * R.y * p2 + p.lobe.z * R.z * p3;
    vec3 cmf = colour_matching_functions(j);
    xyz_layers += cmf * layers_term;
    xyz_base += cmf * (p3 * t.z * p.gap);
}

// dispersive: the host names a dispersive medium (host_table its index per wavelength): with a coating, each
// wavelength refracts its own way (its own Snell angle, Fresnel terms, 1 / nh^2 and table rows). Two loops, so
// that a host of one index computes its directions once.
vec3 single_reflection_brdf(vec3 i, vec3 o, float nh, bool coating, int layer_count, vec3 alphas, vec3 rho_d,
                           sampler2D reflectance_table, sampler2D transmissivity_table, float tau_h,
                           bool dispersive, sampler2D host_table) {
    if (i.z <= 0.0 || o.z <= 0.0) return vec3(0.0);
    vec3 used = layer_mask(layer_count);
    vec3 xyz_layers = vec3(0.0), xyz_base = vec3(0.0);
    if (coating && dispersive) {
        for (int j = 0; j < CMF_COUNT; ++j) {
            HostPaths p = host_paths(i, o, host_index_at(host_table, j), coating, used, alphas, tau_h);
            add_wavelength(j, p, used, reflectance_table, transmissivity_table, xyz_layers, xyz_base);
        }
    } else {
        HostPaths p = host_paths(i, o, nh, coating, used, alphas, tau_h);
        for (int j = 0; j < CMF_COUNT; ++j)
            add_wavelength(j, p, used, reflectance_table, transmissivity_table, xyz_layers, xyz_base);
    }
    return xyz_to_rgb(xyz_layers) + rho_d * (1.0 / PI) * xyz_to_rgb(xyz_base);
}

// The coating's Dirac reflection (Eq. 34's f_r,0) in RGB: F flat (white is rgb (1, 1, 1)) in a host of one
// index, the RGB of F's spectrum in a dispersive one (twin of explorer.physics.layered.coating_rgb).
vec3 coating_rgb(float cos_theta, float nh, bool coating, bool dispersive, sampler2D host_table) {
    if (!coating) return vec3(0.0);
    if (!dispersive) return vec3(coating_reflectance(cos_theta, nh));
    vec3 xyz = vec3(0.0);
    for (int j = 0; j < CMF_COUNT; ++j)
        xyz += colour_matching_functions(j) * coating_reflectance(cos_theta, host_index_at(host_table, j));
    return xyz_to_rgb(xyz);
}

// Multiple scattering (twin of BraggStackModel.brdf): Eq. 34 plus the host's lobe (lib/multiscatter.glsl) times its weight.
vec3 compensation_lobe(vec3 i, vec3 o, sampler2D lobe_table) {
    int ki, ko;
    float fi, fo;
    if (!compensation_cell(i, o, ki, fi, ko, fo)) return vec3(0.0);
    vec3 low = mix(texelFetch(lobe_table, ivec2(ko, ki), 0).rgb, texelFetch(lobe_table, ivec2(ko + 1, ki), 0).rgb, fo);
    vec3 high = mix(texelFetch(lobe_table, ivec2(ko, ki + 1), 0).rgb, texelFetch(lobe_table, ivec2(ko + 1, ki + 1), 0).rgb, fo);
    return mix(low, high, fi);
}

vec3 compensated_brdf(vec3 i, vec3 o, float nh, bool coating, int layer_count, vec3 alphas, vec3 rho_d,
                      sampler2D reflectance_table, sampler2D transmissivity_table, sampler2D lobe_table, float weight,
                      float tau_h, bool dispersive, sampler2D host_table) {
    return single_reflection_brdf(i, o, nh, coating, layer_count, alphas, rho_d, reflectance_table, transmissivity_table, tau_h,
                                  dispersive, host_table)
         + weight * compensation_lobe(i, o, lobe_table);
}

// The smooth limit's specular colour at incidence cos_theta (what the gradient and sphere views show):
// F + (1 - F)^2 sum_l R_l(theta') prod_{k<l} (1 - R_k(theta'))^2, theta' the refracted angle (without a
// coating: theta' = theta, F = 0). Smooth layers transmit 1 - R (the rough layer's integrated
// transmissivity would exceed it beside band edges: see explorer.physics.layered.stack_specular_rgb).
// exact_transmittance: natural (absorbing) layers transmit transmittance_table's T < 1 - R (the host's exact table).
// Where a coated host disperses (dispersive, host_table), theta', F and the gaps are taken per wavelength, and F
// is a spectrum.
vec3 stack_specular_rgb(float cos_theta, float nh, bool coating, int layer_count, sampler2D reflectance_table, float tau_h,
                        bool exact_transmittance, sampler2D transmittance_table, bool dispersive, sampler2D host_table) {
    bool per_wavelength = coating && dispersive;
    float c0 = clamp(cos_theta, 0.0, 1.0), s0 = sqrt(max(1.0 - c0 * c0, 0.0));
    float c = c0, s = s0;
    float F = 0.0, through = 1.0;
    if (coating) {
        F = coating_reflectance(c0, nh);
        through = (1.0 - F) * (1.0 - F);
        s = s0 / nh;
        c = sqrt(max(1.0 - s * s, 0.0));
    }
    int k;
    float f;
    table_row(atan(s, c), k, f);
    vec3 used = layer_mask(layer_count);
    float g = gap_transmittance(tau_h, c);
    g *= g;  // a gap down and up at theta'
    through *= g;
    vec3 xyz = vec3(0.0);
    for (int j = 0; j < CMF_COUNT; ++j) {
        float spectral_F = 0.0;
        if (per_wavelength) {  // this wavelength's own refraction and Fresnel terms
            float n = host_index_at(host_table, j);
            spectral_F = coating_reflectance(c0, n);
            s = s0 / n;
            c = sqrt(max(1.0 - s * s, 0.0));
            table_row(atan(s, c), k, f);
            g = gap_transmittance(tau_h, c);
            g *= g;
            through = (1.0 - spectral_F) * (1.0 - spectral_F) * g;
        }
        vec3 R = table_fetch(reflectance_table, j, k, f) * used;
        vec3 t;
        if (exact_transmittance) {
            vec3 T = table_fetch(transmittance_table, j, k, f);
            t = T * T * g;
        } else {
            t = (1.0 - R) * (1.0 - R) * g;
        }
        xyz += colour_matching_functions(j) * (through * (R.x + t.x * (R.y + t.y * R.z)) + spectral_F);
    }
    if (per_wavelength) return xyz_to_rgb(xyz);
    return xyz_to_rgb(xyz) + vec3(F);  // F is flat: white has rgb (1, 1, 1)
}

// Eq. 31 with the wavelength-averaged numerator: the probability of transmission through a layer.
float transmission_probability(float mean_transmissivity, float cos_theta, float alpha) {
    return clamp(2.0 * mean_transmissivity / (1.0 + smith_G1(cos_theta, alpha)), 0.0, 1.0);
}

// Eq. 35: the probability that the reflection happens on layer l (returned in p_refl, 0 beyond the used
// layers), the coating's transmission being p_trans_0 = 1 - F; returns the probability of reaching the base.
// sampling_table: 361 x 1, channel l the wavelength average of layer l's f_t cos theta.
float layer_choice_probabilities(float cos_theta, float nh, bool coating, int layer_count, vec3 alphas,
                                 sampler2D sampling_table, out vec3 p_refl) {
    float c = clamp(cos_theta, 0.0, 1.0), s = sqrt(max(1.0 - c * c, 0.0));
    float reach = 1.0;
    if (coating) {
        reach = 1.0 - coating_reflectance(c, nh);
        s /= nh;
        c = sqrt(max(1.0 - s * s, 0.0));
    }
    int k;
    float f;
    table_row(atan(s, c), k, f);
    vec3 mean_t = mix(texelFetch(sampling_table, ivec2(k, 0), 0).rgb, texelFetch(sampling_table, ivec2(k + 1, 0), 0).rgb, f);
    p_refl = vec3(0.0);
    for (int l = 0; l < MAX_LAYERS; ++l) {
        if (l >= layer_count) break;
        float p_trans = transmission_probability(mean_t[l], c, alphas[l]);
        p_refl[l] = (1.0 - p_trans) * reach;
        reach *= p_trans;
    }
    return reach;
}
