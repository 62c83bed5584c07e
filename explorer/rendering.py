"""
Any view of a material by any engine: the render service that ``bragg-explorer render``, the app and ``explorer/dev``
call. :func:`render_material` draws a view headless; :func:`gl_inputs` says what the GL engine binds for a view (its
light, uniforms, tables, environment), and :func:`request_view` hands that to one of the app's progressive jobs
(:class:`explorer.gpu.progressive.ProgressiveView`, drawn in row bands within a frame's budget), so that the app's
images and the command's are one description of the view.

It only dispatches: the GL engine draws with :class:`explorer.gpu.Renderer` (meshes: :mod:`explorer.gpu.mesh`; the env
view: :mod:`explorer.gpu.env`), the numpy engine with the material's twin (:func:`explorer.views.render.render_numpy`),
the position-free engine by :mod:`explorer.views.position_free`, and Mitsuba's env view by
:func:`explorer.mitsuba.scene.render_env_mitsuba`. Progress and warnings go to the caller's callbacks.
"""

from __future__ import annotations

from typing import Callable, Mapping

import numpy as np

from explorer.errors import LocatedError
from explorer.materials.brd import Material, MaterialError, round_integer

#: The engines of :func:`render_material`.
ENGINES = ("gl", "numpy", "position-free", "mitsuba")

#: ``progress_printer(label, unit)`` makes a ``progress(done, total)`` for a long render.
ProgressPrinter = Callable[[str, str], Callable[[int, int], None]]


def check_numpy_size(width: int, height: int) -> None:
    """The numpy engine's image budget: the GL engine's (:data:`explorer.gpu.context.MAX_IMAGE_BYTES`), without a context."""
    from explorer.gpu.context import MAX_IMAGE_BYTES

    pixels = MAX_IMAGE_BYTES // 16
    if width * height > pixels:
        raise LocatedError("--size", None, f"{width}x{height} is more than the {pixels} pixels of an image "
                                           f"(a float image under {MAX_IMAGE_BYTES >> 20} MiB)")


def gl_inputs(view: str, *, light=None, plot=None, fill: float | None = None, surface: Mapping | None = None,
              inputs: Mapping | None = None, environment=None, uniforms: Mapping | None = None) -> dict:
    """
    What the GL engine binds to draw ``view``: the keyword arguments ``light``, ``uniforms``, ``inputs`` and
    ``environment`` of :meth:`explorer.gpu.Renderer.render` and of
    :meth:`explorer.gpu.progressive.ProgressiveView.request`. ``plot``: a plot view's settings
    (:func:`explorer.views.plots.gl_uniforms`); ``fill``: the lit view's environment fill (:mod:`explorer.views.fill`,
    None: not bound); ``surface``: the textured view's tables and uniforms (a surface texture's ``gl_arguments``);
    ``inputs``: other tables (a mesh's normals); ``uniforms``: a view's own (the slice's ``slice_phi_d``). ``light`` is
    passed as given (``(theta, phi)`` degrees to ``render``, a direction to a progressive job).
    """
    from explorer.views.geometry import VIEW_REGISTRY

    bound = dict(uniforms or {})
    tables = inputs or None
    if surface is not None:
        bound.update(surface.get("uniforms") or {})
        # The surface's own mapping, not a copy: a progressive job without an inputs_key knows its tables by identity.
        tables = surface.get("inputs") if not tables else {**tables, **(surface.get("inputs") or {})}
    if view in VIEW_REGISTRY and VIEW_REGISTRY[view].plot is not None:
        from explorer.views.plots import gl_uniforms

        bound.update(gl_uniforms(view, plot))
    elif fill is not None:
        bound["fill"] = float(fill)
    return {"light": light, "uniforms": bound, "inputs": tables or None, "environment": environment}


def request_view(job, material: Material, values, view: str, size: tuple[int, int], *, dragging: bool = False,
                 inputs_key=None, **described) -> None:
    """
    Ask the app's progressive ``job`` (a :class:`explorer.gpu.progressive.ProgressiveView`) for ``view`` of ``material``
    at ``values`` and ``size``, bound as :func:`gl_inputs` describes it (``described``: its keywords). The job draws
    it in row bands over the frames (a preview while ``dragging``); ``inputs_key`` names the tables (arrays are not
    compared).
    """
    job.request(material, values, view, size, dragging=dragging, inputs_key=inputs_key, **gl_inputs(view, **described))


def render_material(
    material: Material, values: dict, view: str, width: int, height: int, engine: str,
    light: tuple[float, float] | None = None, thickness=None, environment=None, spp: int | None = None,
    variant: str | None = None, mesh=None, background: bool = False, plot=None, fill: float = 0.0,
    progress_printer: ProgressPrinter | None = None, warn: Callable[[str], None] | None = None,
    checked: Callable[[], None] = lambda: None, renderer=None,
) -> np.ndarray:
    """
    One view of a material as a linear float RGB image ``(height, width, 3)``, by ``engine`` (:data:`ENGINES`): on the
    GPU (``gl``), by its numpy twin (``numpy``), by the position-free reference (``position-free``: the lit and slice
    views of a layered Bragg stack) or by Mitsuba (``mitsuba``: the env view, ``variant``). ``thickness`` (an
    :class:`explorer.views.thickness.ThicknessTexture` or a Bragg texture) for the ``textured`` view (and the env view's
    surface); ``environment`` (an :class:`explorer.views.env.EnvironmentMap`, default the shipped one) and ``spp``
    (samples per pixel; default 64) for the ``env`` view and the position-free engine; ``mesh`` (an
    :class:`explorer.views.mesh.Mesh`) drawn instead of the sphere in the ``lit`` and ``env`` views; ``plot`` (an
    :class:`explorer.views.plots.PlotSettings`) for the plot views; ``fill``, the ``lit`` view's environment fill
    (:mod:`explorer.views.fill`), 0 without. ``progress_printer(label, unit)`` reports long renders; ``warn(message)``
    is told of samples dropped; ``checked()`` once the input has passed its checks (sizes against this GL's
    limits), where the work that cannot count its steps begins. ``renderer``: an :class:`explorer.gpu.Renderer` to
    draw the GL views with (a caller that holds one: a second context made current would take its calls), else a new one.
    """
    if material.measured is not None:
        from explorer.views.geometry import VIEW_REGISTRY

        if VIEW_REGISTRY[view].evaluates not in ("brdf", "environment"):
            shown = ", ".join(name for name, v in VIEW_REGISTRY.items() if v.evaluates in ("brdf", "environment"))
            raise MaterialError(material.path, None, f"a measured BRDF (MERL) has no {view} view (it has no reflectance(cos_theta) "
                                                     f"nor film thickness); its views: {shown}")
    if engine == "position-free":
        from explorer.views.position_free import render_position_free

        return render_position_free(material, values, view, width, height, light, spp, progress_printer)
    spp = spp or 64
    if view == "env" and engine == "mitsuba":
        if thickness is not None:
            raise LocatedError("--engine", None, "the Mitsuba plugins have no surface texture: --engine gl or numpy")
        checked()
        return _render_env_mitsuba(material, values, width, height, environment, spp, variant, warn)
    if view == "env":
        return _render_env(material, values, width, height, engine, environment, spp, mesh, background, thickness,
                           progress_printer, warn)
    if view == "textured":
        from explorer.views.surface_texture import check_texture_kind, default_texture
        from explorer.views.thickness import check_prefilter

        # What the texture varies is the material's declaration ('# texture:'), not its name.
        check_texture_kind(material)
        if "medium_n2" in values:  # a Bragg mirror's natural layers have no texture mapping (explorer.physics.natural)
            from explorer.materials.models import natural_mirror_of

            if natural_mirror_of(values) is not None:
                raise MaterialError(material.path, None, "the textured view varies the paper's mirror only: without k1, k2, "
                                                         "sigma and media (the sphere, lit and env views show them)")
        thickness = default_texture(material) if thickness is None else thickness
        check_prefilter(round_integer(values.get("method", 0)), thickness.prefilter)
    if mesh is not None and thickness is not None:
        if mesh.uvs is None:
            raise LocatedError("--mesh", None, f"{mesh.name} has no texture coordinates ('vt'): no surface texture on it")
        if thickness.prefilter:
            raise LocatedError("--prefilter", None, "prefiltering is the sphere's, not a mesh's")
    if engine == "numpy":
        from explorer.materials.models import model_for
        from explorer.views.geometry import BRDF_VIEWS
        from explorer.views.render import render_numpy

        model = model_for(material, values)
        if model is None:
            raise MaterialError(material.path, None, "this material has no numpy twin (no known '# model:' line)")
        if view in BRDF_VIEWS and not callable(getattr(model, "brdf", None)):
            raise MaterialError(material.path, None, f"its numpy twin has no brdf(): no {view} view with --engine numpy")
        check_numpy_size(width, height)
        checked()
        return render_numpy(model, view, width, height, light=light, thickness=thickness, mesh=mesh, plot=plot, environment=environment,
                            fill=fill)
    from explorer.gpu import Renderer
    from explorer.views.geometry import view_named

    renderer = Renderer() if renderer is None else renderer
    renderer.limits.check_target(width, height)  # this GL's limits, before any work at this size
    if view == "textured":
        renderer.limits.check_texture(thickness.d_inc.shape[1], thickness.d_inc.shape[0], 1, thickness.source)
        checked()
        if mesh is not None:
            from explorer.gpu.mesh import render_mesh

            return render_mesh(renderer, material, values, view, mesh, width, height, light=light,
                               surface=thickness.gl_arguments(material, values, width, height))
        return renderer.render(material, values, view, width, height,
                               **gl_inputs(view, light=light, surface=thickness.gl_arguments(material, values, width, height)))
    view_named(view)  # an unknown view: one line listing them
    if view != "textured":
        checked()
    if mesh is not None:
        from explorer.gpu.mesh import render_mesh

        return render_mesh(renderer, material, values, view, mesh, width, height, light=light, environment=environment,
                           uniforms=gl_inputs(view, fill=fill)["uniforms"])
    return renderer.render(material, values, view, width, height,
                           **gl_inputs(view, light=light, plot=plot, fill=fill, environment=environment))


def _render_env(material: Material, values: dict, width: int, height: int, engine: str, environment, spp: int, mesh,
                background: bool, surface, progress_printer: ProgressPrinter | None, warn) -> np.ndarray:
    """The env view (:func:`explorer.gpu.env.render_env`)."""
    from explorer.gpu.env import render_env

    if engine == "numpy":
        from explorer.materials.models import model_for

        model = model_for(material, values)
        if model is None or not callable(getattr(model, "brdf", None)):
            raise MaterialError(material.path, None, "its numpy twin has no brdf(): no env view with --engine numpy")
        check_numpy_size(width, height)
    unit = "samples per pixel" if engine == "gl" else "pixels"
    return render_env(material, values, width, height, engine=engine, environment=environment, spp=spp,
                      progress=progress_printer("env", unit) if progress_printer else None, warn=warn, mesh=mesh,
                      background=background, surface=surface)


def _render_env_mitsuba(material: Material, values: dict, width: int, height: int, environment, spp: int,
                        variant: str | None, warn) -> np.ndarray:
    """The env view by Mitsuba (:func:`explorer.mitsuba.scene.render_env_mitsuba`), its LLVM fallback told to ``warn``."""
    from explorer.materials.twins import capabilities_of, supporting
    from explorer.mitsuba.scene import render_env_mitsuba

    if not capabilities_of(material).supports("mitsuba"):
        raise MaterialError(material.path, None, f"no Mitsuba plugin for this material (plugins: {', '.join(supporting('mitsuba'))})")
    return render_env_mitsuba(material, values, width, height, spp, environment, variant, note=warn)
