"""
OpenGL contexts: a headless moderngl context through EGL (Mesa's llvmpipe without a GPU), and what
every program shares (the GLSL version, the full-screen vertex shader).
"""

from __future__ import annotations

GLSL_VERSION = "330 core"
EGL_PACKAGES = "libegl1 libgl1 libegl-mesa0 libgl1-mesa-dri"

VERTEX_SHADER = f"""#version {GLSL_VERSION}
// A full-screen triangle from gl_VertexID: no vertex buffer needed.
void main() {{
    vec2 p = vec2(float((gl_VertexID << 1) & 2), float(gl_VertexID & 2));
    gl_Position = vec4(2.0 * p - 1.0, 0.0, 1.0);
}}
"""


class GLUnavailable(RuntimeError):
    """No OpenGL 3.3 context could be created (one-line message naming what to install)."""


def create_context():
    """A headless moderngl context through EGL, or :class:`GLUnavailable` saying what is missing."""
    try:
        import moderngl
    except ImportError as error:  # pragma: no cover - a dependency of the package
        raise GLUnavailable(f"moderngl is not installed ({error}); run: python3 -m explorer") from None
    try:
        return moderngl.create_standalone_context(require=330, backend="egl")
    except Exception as error:  # glcontext raises plain Exceptions
        reason = str(error).strip().splitlines()[0] if str(error).strip() else type(error).__name__
        raise GLUnavailable(
            f"no OpenGL through EGL ({reason}); install Mesa's EGL: apt-get install {EGL_PACKAGES}"
        ) from None
