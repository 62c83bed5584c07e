"""
The OpenGL host: contexts (:mod:`.context`), a material's program per view (:mod:`.programs`), the
numpy models' tables (:mod:`.tables`), the :class:`Renderer` and its one draw primitive
(:meth:`Renderer.draw`), and what draws through it progressively: the app's views
(:mod:`.progressive`, :mod:`.display`) and the environment view's Monte Carlo (:mod:`.env`).
"""

from explorer.gpu.context import GLLimitError, GLLimits, GLUnavailable, create_context, gl_limits
from explorer.gpu.renderer import Renderer

__all__ = ["GLLimitError", "GLLimits", "GLUnavailable", "Renderer", "create_context", "gl_limits"]
