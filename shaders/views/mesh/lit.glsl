// The lit view of a mesh: lit.glsl with each pixel's normal read from the mesh's rasterised normals
// (uniform mesh_normals, explorer/gpu/mesh.py) instead of the sphere's (view_surface in lib/views.glsl).
// Twin: explorer.views.render.render_numpy(model, 'lit', ..., mesh=...).
#define MESH_NORMALS
#include "views/lit.glsl"
