"""
A mesh in the ``lit``, ``textured`` and ``env`` views on the GPU: one rasterising pass writes each pixel's
interpolated normal (and 1 where the mesh covers it) and texture coordinates into float textures, with a depth
test; the views' programs (``shaders/views/mesh/*.glsl``: the sphere's templates with ``MESH_NORMALS`` defined)
read them instead of the sphere's normal and planar coordinates. Twin: :func:`explorer.views.mesh.rasterise`
(the same camera, :func:`explorer.views.mesh.view_space`).
"""

from __future__ import annotations

import numpy as np

from explorer.gpu.context import GLSL_VERSION
from explorer.views.mesh import Mesh, aspect_scale, view_space

#: The view templates of a mesh, by the sphere view they replace.
MESH_TEMPLATES = {"lit": "mesh/lit", "env": "mesh/env", "textured": "mesh/textured"}

_VERTEX = f"""#version {GLSL_VERSION}
in vec3 position;
in vec3 normal;
in vec2 uv;
uniform vec2 scale;  // view x, y to clip space (the shorter side spans [-1, 1])
out vec3 interpolated_normal;
out vec2 interpolated_uv;
void main() {{
    interpolated_normal = normal;
    interpolated_uv = uv;
    gl_Position = vec4(position.xy * scale, -0.5 * position.z, 1.0);  // nearer (larger z) -> smaller depth
}}
"""
_FRAGMENT = f"""#version {GLSL_VERSION}
in vec3 interpolated_normal;
in vec2 interpolated_uv;
layout(location = 0) out vec4 surface;
layout(location = 1) out vec4 texture_coordinates;
void main() {{
    surface = vec4(interpolated_normal, 1.0);
    texture_coordinates = vec4(interpolated_uv, 0.0, 1.0);
}}
"""


def mesh_normals(renderer, mesh: Mesh, width: int, height: int) -> np.ndarray:
    """
    The GL pass: ``(height, width, 4)`` float32 in GL's row order (row 0 at the bottom, as the views'
    ``texelFetch(mesh_normals, ivec2(gl_FragCoord.xy))`` reads it): the interpolated normal, and 1 where
    the mesh covers the pixel centre (0 and no normal elsewhere).
    """
    return mesh_surface(renderer, mesh, width, height)[0]


def mesh_surface(renderer, mesh: Mesh, width: int, height: int) -> tuple[np.ndarray, np.ndarray]:
    """
    The GL pass: :func:`mesh_normals`'s image and the interpolated texture coordinates ``(height, width, 4)``
    (``u, v, 0, 1`` where the mesh covers the pixel; zeros for a mesh without coordinates), in the same row order.
    """
    import moderngl

    ctx = renderer.ctx
    renderer.limits.check_target(width, height)
    positions, normals = view_space(mesh)
    program = getattr(renderer, "_mesh_normals_program", None)
    if program is None:  # compiled once per renderer (its context)
        program = renderer._mesh_normals_program = ctx.program(vertex_shader=_VERTEX, fragment_shader=_FRAGMENT)
    uvs = np.zeros((len(positions), 2)) if mesh.uvs is None else mesh.uvs
    vertices = ctx.buffer(np.ascontiguousarray(np.concatenate([positions, normals, uvs], axis=1), dtype="f4").tobytes())
    indices = ctx.buffer(np.ascontiguousarray(mesh.triangles, dtype="i4").tobytes())
    array = ctx.vertex_array(program, [(vertices, "3f 3f 2f", "position", "normal", "uv")], index_buffer=indices, index_element_size=4)
    # moderngl binds its last bound framebuffer again after making one, and binding a deleted one is
    # GL_INVALID_OPERATION (which the app's ImGui backend raises): a live one is bound first and again at the
    # end, before ours is released (the last one bound if alive, else the screen, or a standalone's 0).
    bound = ctx.fbo
    alive = isinstance(bound, moderngl.Framebuffer) and type(getattr(bound, "mglo", None)).__name__ != "InvalidObject"
    previous = bound if alive else ctx.screen or ctx.detect_framebuffer(0)
    previous.use()
    colour = ctx.texture((width, height), 4, dtype="f4")
    coordinates = ctx.texture((width, height), 4, dtype="f4")
    depth = ctx.depth_renderbuffer((width, height))
    framebuffer = ctx.framebuffer(color_attachments=[colour, coordinates], depth_attachment=depth)
    try:
        program["scale"].value = aspect_scale(width, height)
        framebuffer.use()
        framebuffer.clear(0.0, 0.0, 0.0, 0.0, depth=1.0)
        ctx.enable(moderngl.DEPTH_TEST)
        try:
            array.render(moderngl.TRIANGLES)
        finally:
            ctx.disable(moderngl.DEPTH_TEST)
        data = np.frombuffer(colour.read(), dtype=np.float32).reshape(height, width, 4)
        uv = np.frombuffer(coordinates.read(), dtype=np.float32).reshape(height, width, 4)
        return data.copy(), uv.copy()
    finally:
        previous.use()
        renderer.resources.release(framebuffer, depth, colour, coordinates, array, indices, vertices)


def render_mesh(renderer, material, values, view: str, mesh: Mesh, width: int, height: int, *, light=None, environment=None,
                uniforms=None, surface=None) -> np.ndarray:
    """
    The ``lit`` or ``textured`` view of ``mesh``: ``(height, width, 3)`` float32 linear RGB, rows from the top (see
    :meth:`Renderer.render`); ``surface``: the textured view's tables and uniforms (a surface texture's ``gl_arguments``).
    """
    normals, uvs = mesh_surface(renderer, mesh, width, height)
    inputs = {"mesh_normals": normals, "mesh_uvs": uvs, **((surface or {}).get("inputs") or {})}
    return renderer.render(material, values, MESH_TEMPLATES[view], width, height, light=light, inputs=inputs,
                           environment=environment, uniforms={**(uniforms or {}), **((surface or {}).get("uniforms") or {})})
