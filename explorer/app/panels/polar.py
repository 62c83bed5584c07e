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

    def draw(self, imgui) -> None:
        from imgui_bundle import implot

        state = self.state
        job = self.scheduler.job("polar")
        job.request(state.material, state.values, "scatter", (POLAR_SAMPLES, 1), light=light_vector(state.light, state.camera), dragging=False)
        if job.complete and job.generation != self._generation:
            self._curve = data.polar_curve(job.read())
            self._generation = job.generation
        imgui.text(f"plane of incidence (light theta = {state.light[0]:.1f} deg); radius = BRDF (1/sr)")
        if self._curve is None:
            return
        theta, brdf = self._curve
        if implot.begin_plot("polar", imgui.ImVec2(-1, -1), implot.Flags_.equal):
            implot.setup_axes("", "")
            radians = np.radians(theta)
            for channel, colour in enumerate(((1, 0.3, 0.3, 1), (0.3, 1, 0.3, 1), (0.4, 0.5, 1, 1))):
                r = np.clip(brdf[:, channel], 0.0, None)
                implot.plot_line("RGB"[channel], r * np.sin(radians), r * np.cos(radians), implot.Spec(line_color=imgui.ImVec4(*colour)))
            implot.end_plot()

    def gl_jobs(self) -> list:
        return [self.scheduler.job("polar")]
