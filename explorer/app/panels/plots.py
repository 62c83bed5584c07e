"""
The Plots window: BRDF Explorer's plots (:mod:`explorer.views.plots`), one chosen from the registry's plot
views (``theta_v``, ``theta_h``, ``theta_d``, ``lobe3d``, ``albedo``), with their sliders, log scale, channel
and N.L; drawn by the GPU (the views' shaders) and plotted with ImPlot (the lobe with ImPlot3D).
"""

from __future__ import annotations

import numpy as np

from explorer.rendering import request_view
from explorer.app.panels.base import Panel, combo
from explorer.views.geometry import PLOT_VIEWS, light_direction, view_named
from explorer.views.plots import CHANNELS, PLOT_SETTINGS, PlotSettings, abscissa, cos_light, plotted

#: Samples of a curve, and of the lobe (phi_o x theta_o), in the window; the albedo's (each costs a quadrature).
CURVE_SAMPLES = 256
LOBE_SAMPLES = (64, 24)
ALBEDO_SAMPLES = 45
SLIDERS = {"theta_d": ("theta_d", 0.0, 90.0), "theta_h": ("theta_h", 0.0, 90.0), "phi_v": ("phi_v", -180.0, 180.0)}
COLOURS = {"r": (1.0, 0.3, 0.3, 1.0), "g": (0.3, 1.0, 0.3, 1.0), "b": (0.4, 0.5, 1.0, 1.0), "luminance": (0.9, 0.9, 0.9, 1.0)}


def plot_size(view: str) -> tuple[int, int]:
    if view == "albedo":
        return ALBEDO_SAMPLES, 1
    return LOBE_SAMPLES if view_named(view).plot == "lobe" else (CURVE_SAMPLES, 1)


class PlotsPanel(Panel):
    title = "Plots"
    dock = "right_top"
    gl_order = 6
    #: GL time (ms) a frame gives the plot while a slider moves: a curve (256 x 1) or the lobe (64 x 24) draws whole.
    drag_budget_ms = 4.0

    def __init__(self, app):
        super().__init__(app)
        self.view = PLOT_VIEWS[0]
        self.settings = PlotSettings()
        self._values = None  # the finished image's plotted values
        self._generation = -1
        self._key = None

    def _light(self) -> tuple[float, float]:
        theta, phi = (float(v) for v in self.state.light[:2])
        return min(max(theta, 0.0), 90.0), phi  # the plots' light lies above the surface

    def draw(self, imgui) -> None:
        from dataclasses import replace

        self.view = combo(self.state, "plot", self.view, [(n, n) for n in PLOT_VIEWS], self.view, "plot", "plot_combo") or self.view
        settings = self.settings
        for name in PLOT_SETTINGS[self.view]:
            label, low, high = SLIDERS[name]
            _, value = imgui.slider_float(label, float(getattr(settings, name)), low, high, "%.1f deg")
            settings = replace(settings, **{name: float(value)})
        _, log = imgui.checkbox("log10(1 + x)", settings.log)
        imgui.same_line()
        _, ndotl = imgui.checkbox("x N.L", settings.ndotl)
        imgui.same_line()
        imgui.set_next_item_width(110)
        _, channel = imgui.combo("channel", CHANNELS.index(settings.channel), list(CHANNELS))
        self.settings = settings = replace(settings, log=log, ndotl=ndotl, channel=CHANNELS[channel])
        light = self._light()
        job = self.scheduler.job("plot")
        size = plot_size(self.view)
        # The values whose tables are ready (draft ones while dragging), as the sphere's: none built on the spot.
        values = self.scheduler.prefetcher.values(self.state.material, self.state.values, self.app.dragging)
        request_view(job, self.state.material, values, self.view, size, light=tuple(float(c) for c in light_direction(light)),
                     plot=settings, dragging=self.app.dragging)
        key = (self.view, settings, light)
        if not job.complete:  # a new curve on its way (scripts wait_for it)
            self.state.plots = {"running": True}
        elif job.generation != self._generation or key != self._key:
            image = job.read().astype(np.float64)
            self._values = plotted(image, settings, cos_light(self.view, size[0], size[1], light_direction(light), settings))
            self._generation, self._key = job.generation, key
            self.state.plots = {"view": self.view, "settings": vars(settings), "light": list(light), "size": list(size),
                                "values": self._values.tolist()}
        note = {"theta_v": f"light ({light[0]:.0f}, {light[1]:.0f}) deg", "lobe3d": f"light ({light[0]:.0f}, {light[1]:.0f}) deg"}
        imgui.text_wrapped(f"{self.view}: {note.get(self.view, 'phi_d = 90 deg' if self.view != 'albedo' else 'directional albedo')}"
                           + ("" if job.complete else f"  (refining {100 * job.progress:.0f}%)") + (f"  {job.error}" if job.error else ""))
        if self._values is None or self._key is None or self._key[0] != self.view:
            return
        if view_named(self.view).plot == "lobe":
            self._draw_lobe(light)
        else:
            self._draw_curves(imgui)

    def _channels(self) -> tuple[str, ...]:
        return ("r", "g", "b") if self.settings.channel == "rgb" else (self.settings.channel,)

    def _draw_curves(self, imgui) -> None:
        from imgui_bundle import implot

        x = abscissa(self.view, self._values.shape[1])
        if implot.begin_plot(f"##{self.view}", imgui.ImVec2(-1, -1)):
            implot.setup_axes(self.view.replace("albedo", "theta_i") + " (deg)", "")
            for k, name in enumerate(self._channels()):
                implot.plot_line(name, x, np.ascontiguousarray(self._values[0, :, k]),
                                 implot.Spec(line_color=imgui.ImVec4(*COLOURS[name])))
            implot.end_plot()

    def _draw_lobe(self, light) -> None:
        from imgui_bundle import imgui, implot3d

        if implot3d.get_current_context() is None:
            implot3d.create_context()
        from explorer.views.plots import lobe_directions

        height, width = self._values.shape[:2]
        theta_o, phi_o = lobe_directions(width, height)
        radius = np.maximum(self._values[..., 0] if len(self._channels()) == 1 else self._values.mean(axis=-1), 0.0)
        xs, ys, zs = (np.ascontiguousarray(a.ravel(), dtype=np.float64) for a in (
            radius * np.sin(theta_o) * np.cos(phi_o), radius * np.sin(theta_o) * np.sin(phi_o), radius * np.cos(theta_o)))
        if implot3d.begin_plot("##lobe3d", imgui.ImVec2(-1, -1)):
            extent = float(max(radius.max(), 1e-6))
            implot3d.setup_axes_limits(-extent, extent, -extent, extent, 0.0, extent, implot3d.Cond_.always)
            implot3d.plot_surface("lobe", xs, ys, zs, width, height)
            t, p = np.radians(light[0]), np.radians(light[1])
            implot3d.plot_line("light", np.array([0.0, extent * np.sin(t) * np.cos(p)]), np.array([0.0, extent * np.sin(t) * np.sin(p)]),
                               np.array([0.0, extent * np.cos(t)]))
            implot3d.end_plot()

    def gl_jobs(self) -> list:
        return [self.scheduler.job("plot")]
