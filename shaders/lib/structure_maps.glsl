// Structure maps (design --target-image's output): texture_mapping TEXTURE_MAPS gives each texel its own structure,
// the surface value the nearest texel's index (row-major). The host's table holds STRUCTURE_TEXELS RGBA texels a map
// texel: the fields a material declares it maps, in order, the last slot 1 on the maps' mask. Twin:
// explorer/physics/structure_maps.py (structure_table, structure_texels).
#include "generated/structure_maps.glsl"  // the constants shared with explorer/physics (generated at assembly)

// Only in the views that read a surface texture (the host defines SURFACE_TEXTURE): no sampler in a .brdf export.
#ifdef SURFACE_TEXTURE
// The texel's two RGBA texels (its fields); false off the mask.
bool structure_texels(sampler2D table, float T, out vec4 a, out vec4 b) {
    int width = textureSize(table, 0).x / STRUCTURE_TEXELS;
    int index = int(T);  // an integer below 2^24: exact in float32
    ivec2 texel = ivec2(STRUCTURE_TEXELS * (index % width), index / width);
    a = texelFetch(table, texel, 0);
    b = texelFetch(table, texel + ivec2(1, 0), 0);
    return b.w > 0.5;
}
#endif
