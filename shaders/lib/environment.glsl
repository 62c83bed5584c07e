// An equirectangular environment map's radiance toward a direction (the env view's environment, and what a
// smooth mirror reflects in the lit view). Twin: explorer.views.env.EnvironmentMap.radiance.
//
// Convention: linear RGB, texture row 0 (v = 0) at the zenith +y (the sphere's screen up), v = theta / pi
// with theta the angle from +y; the centre column u = 0.5 faces away from the viewer (-z) and u = 0.75 is
// +x: u = 0.5 + atan(x, -z) / 2 pi, less the probe's turn about +y (a fraction of a turn). Both angles come
// from atan, not acos: Mesa's inverse trigonometry is a polynomial with errors near 1e-4 rad at worst, a
// small fraction of a texel of any environment up to 8k wide, and atan(length(d.xz), d.y) stays accurate at
// the poles where acos(d.y) loses digits. The host binds it LINEAR, repeat in u, clamp in v; level 0.
vec3 environment_radiance(sampler2D map, float turn, vec3 d) {
    float u = 0.5 + atan(d.x, -d.z) * 0.15915494309189535 - turn;  // 1 / (2 pi)
    float v = atan(length(d.xz), d.y) * 0.3183098861837907;  // 1 / pi
    return textureLod(map, vec2(u, v), 0.0).rgb;
}
