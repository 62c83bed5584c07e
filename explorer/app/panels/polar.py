"""The Polar window: the BRDF in the plane of incidence (the scatter view's middle row)."""

from __future__ import annotations

import numpy as np

from explorer.app import data
from explorer.app.camera import light_vector
from explorer.app.panels.base import Panel

POLAR_SAMPLES = 181


class PolarPanel(Panel):
    title = "Polar"
    dock = "right_top"
    gl_order = 5

    def __init__(self, app):
        super().__init__(app)
        self._curve = None
        self._generation = -1  # the scatter row the curve was computed from
        self._fitted_material = None  # the material the axes were last fitted to (refit when it changes)

    def draw(self, imgui) -> None:
        from imgui_bundle import implot

        state = self.state
        job = self.scheduler.job("polar")
        light = light_vector(state.light, state.camera)
        job.request(state.material, state.values, "scatter", (POLAR_SAMPLES, 1), light=light, dragging=False)
        if job.complete and job.generation != self._generation:
            self._curve = data.polar_curve(job.read())
            self._generation = job.generation
        imgui.text_wrapped(f"plane of incidence (light theta = {state.light[0]:.1f} deg); radius = BRDF (1/sr)")
        if self._curve is None:
            return
        theta, brdf = self._curve
        if self._fitted_material is not state.material:  # another material: the axes fit its curve again
            implot.set_next_axes_to_fit()
            self._fitted_material = state.material
        if implot.begin_plot("polar", imgui.ImVec2(-1, -1), implot.Flags_.equal):
            implot.setup_axes("", "")
            radians = np.radians(theta)
            for channel, colour in enumerate(((1, 0.3, 0.3, 1), (0.3, 1, 0.3, 1), (0.4, 0.5, 1, 1))):
                r = np.clip(brdf[:, channel], 0.0, None)
                implot.plot_line("RGB"[channel], r * np.sin(radians), r * np.cos(radians), implot.Spec(line_color=imgui.ImVec4(*colour)))
            # The incident direction, projected on the plane (x toward phi = 0, as the curve's signed theta).
            xs, ys = data.polar_incident(light, float(max(np.clip(brdf, 0.0, None).max(), 1e-6)))
            implot.plot_line("light", xs, ys, implot.Spec(line_color=imgui.ImVec4(1.0, 0.85, 0.2, 1.0), line_weight=2.0))
            implot.end_plot()

    def gl_jobs(self) -> list:
        return [self.scheduler.job("polar")]
