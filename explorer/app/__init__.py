"""
The interactive explorer: a glfw window, Dear ImGui and ImPlot (``imgui-bundle``), moderngl.

``bragg-explorer`` (no argument, with a display) opens it on the default Bragg mirror;
``bragg-explorer open FILE.brd|FILE.brdf [--preset NAME]`` on another material. Its images are the
headless renderer's views (:mod:`explorer.gpu.progressive`: the same programs, bindings and templates),
drawn progressively into offscreen textures shown in docked ImGui windows, one module each in
:mod:`explorer.app.panels`:

* **Sphere**: ``lit`` (one directional light; orbit camera by left-drag, light by right-drag or the
  sliders, zoom by the wheel), ``sphere`` (white furnace; the mirror's reflectance) or ``env``
  (progressive Monte Carlo under the default sky, :mod:`explorer.gpu.env`);
* **Compare**: a split sphere of two methods or two parameter sets (A | B), or their ΔE2000 heat-map;
* **Strips**: Figure 4's θ gradient, one row per method; **Spectrum**: R_λ at one angle (Figure 3);
  **Polar**: the BRDF in the plane of incidence; **Slice** and **Scatter**: BRDF Explorer's views.

The layers: :mod:`.state` (what the window shows, one dataclass), :mod:`.window` (the :class:`App`: the
material's lifecycle, the loop, the menu), :mod:`.panels`, :mod:`.scheduler` (the frame's GL work within
its budget), :mod:`.camera`, :mod:`.screenshots`, :mod:`.script` (scripted sessions: ``--script FILE``
plays synthesised input through ImGui's IO and ``--report`` writes what happened as JSON; the tests and
``bench --app`` use them), and the GUI-free :mod:`.parameter_files` and :mod:`.data`.
"""

from explorer.app.window import DEFAULT_WINDOW, App, AppError, display_available, run_app

__all__ = ["App", "AppError", "DEFAULT_WINDOW", "display_available", "run_app"]
