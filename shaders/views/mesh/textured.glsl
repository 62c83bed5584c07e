// The textured view of a mesh: textured.glsl with each pixel's normal and texture coordinates read from the mesh's
// rasterising pass (uniforms mesh_normals, mesh_uvs; explorer/gpu/mesh.py) instead of the sphere's.
// Twin: explorer.views.render.render_numpy(model, 'textured', ..., mesh=...).
#define MESH_NORMALS
#include "views/textured.glsl"
