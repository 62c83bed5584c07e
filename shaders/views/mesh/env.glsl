// The env view of a mesh: env.glsl with each pixel's normal read from the mesh's rasterised normals
// (uniform mesh_normals, explorer/gpu/mesh.py) instead of the sphere's (view_surface in lib/views.glsl).
// Twin: explorer.views.env.env_integral_numpy(..., mesh=...).
#define MESH_NORMALS
#include "views/env.glsl"
