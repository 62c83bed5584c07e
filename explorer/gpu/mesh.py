"""
A mesh in the ``lit`` and ``env`` views on the GPU: one rasterising pass writes each pixel's interpolated
normal (and 1 where the mesh covers it) into a float texture, with a depth test; the views' programs
(``shaders/views/mesh/lit.glsl``, ``shaders/views/mesh/env.glsl``: the sphere's templates with
``MESH_NORMALS`` defined) read it instead of the sphere's normal. Twin: :func:`explorer.views.mesh.rasterise`
(the same camera, :func:`explorer.views.mesh.view_space`).
"""

from __future__ import annotations

import numpy as np

from explorer.gpu.context import GLSL_VERSION
from explorer.views.mesh import Mesh, aspect_scale, view_space

#: The view templates of a mesh, by the sphere view they replace.
MESH_TEMPLATES = {"lit": "mesh/lit", "env": "mesh/env"}

_VERTEX = f"""#version {GLSL_VERSION}
in vec3 position;
in vec3 normal;
uniform vec2 scale;  // view x, y to clip space (the shorter side spans [-1, 1])
out vec3 interpolated_normal;
void main() {{
    interpolated_normal = normal;
    gl_Position = vec4(position.xy * scale, -0.5 * position.z, 1.0);  // nearer (larger z) -> smaller depth
}}
"""
_FRAGMENT = f"""#version {GLSL_VERSION}
in vec3 interpolated_normal;
out vec4 surface;
void main() {{ surface = vec4(interpolated_normal, 1.0); }}
"""


def mesh_normals(renderer, mesh: Mesh, width: int, height: int) -> np.ndarray:
    """
    The GL pass: ``(height, width, 4)`` float32 in GL's row order (row 0 at the bottom, as the views'
    ``texelFetch(mesh_normals, ivec2(gl_FragCoord.xy))`` reads it): the interpolated normal, and 1 where
    the mesh covers the pixel centre (0 and no normal elsewhere).
    """
    import moderngl

    ctx = renderer.ctx
    renderer.limits.check_target(width, height)
    positions, normals = view_space(mesh)
    program = getattr(renderer, "_mesh_normals_program", None)
    if program is None:  # compiled once per renderer (its context)
        program = renderer._mesh_normals_program = ctx.program(vertex_shader=_VERTEX, fragment_shader=_FRAGMENT)
    vertices = ctx.buffer(np.ascontiguousarray(np.concatenate([positions, normals], axis=1), dtype="f4").tobytes())
    indices = ctx.buffer(np.ascontiguousarray(mesh.triangles, dtype="i4").tobytes())
    array = ctx.vertex_array(program, [(vertices, "3f 3f", "position", "normal")], index_buffer=indices, index_element_size=4)
    # moderngl binds its last bound framebuffer again after making one, and binding a deleted one is
    # GL_INVALID_OPERATION (which the app's ImGui backend raises): a live one is bound first and again at the
    # end, before ours is released (the last one bound if alive, else the screen, or a standalone's 0).
    bound = ctx.fbo
    alive = isinstance(bound, moderngl.Framebuffer) and type(getattr(bound, "mglo", None)).__name__ != "InvalidObject"
    previous = bound if alive else ctx.screen or ctx.detect_framebuffer(0)
    previous.use()
    colour = ctx.texture((width, height), 4, dtype="f4")
    depth = ctx.depth_renderbuffer((width, height))
    framebuffer = ctx.framebuffer(color_attachments=[colour], depth_attachment=depth)
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
        return data.copy()
    finally:
        previous.use()
        renderer.resources.release(framebuffer, depth, colour, array, indices, vertices)


def render_mesh(renderer, material, values, view: str, mesh: Mesh, width: int, height: int, *, light=None, environment=None,
                uniforms=None) -> np.ndarray:
    """The ``lit`` view of ``mesh``: ``(height, width, 3)`` float32 linear RGB, rows from the top (see :meth:`Renderer.render`)."""
    surface = mesh_normals(renderer, mesh, width, height)
    return renderer.render(material, values, MESH_TEMPLATES[view], width, height, light=light, inputs={"mesh_normals": surface},
                           environment=environment, uniforms=uniforms)
