"""The Polar window: the BRDF in the plane of incidence (the scatter view's middle row), of every visible material."""

from __future__ import annotations

import numpy as np

from explorer.app import data
from explorer.app.camera import light_vector
from explorer.app.panels.base import Panel

POLAR_SAMPLES = 181
#: Linear sRGB's luminance weights (ITU-R BT.709): one curve per material when several are overlaid.
LUMINANCE = np.array([0.2126, 0.7152, 0.0722])


class PolarPanel(Panel):
    title = "Polar"
    dock = "right_top"
    gl_order = 5

    def __init__(self, app):
        super().__init__(app)
        self._curves: dict = {}  # job name -> (generation, (theta, brdf))
        self._jobs: list = []  # this frame's job names, in drawing order

    def _job_name(self, entry) -> str:
        return "polar" if entry is None or entry.material is self.state.material else f"polar:{id(entry.material)}"

    def draw(self, imgui) -> None:
        from imgui_bundle import implot

        state = self.state
        entries = state.visible_entries() or [None]
        light = light_vector(state.light, state.camera)
        curves, self._jobs = [], []
        for entry in entries:
            name = self._job_name(entry)
            material, values = (state.material, state.values) if entry is None else (entry.material, entry.values)
            job = self.scheduler.job(name)
            job.request(material, values, "scatter", (POLAR_SAMPLES, 1), light=light, dragging=False)
            self._jobs.append(name)
            cached = self._curves.get(name)
            if job.complete and (cached is None or cached[0] != job.generation):
                cached = (job.generation, data.polar_curve(job.read()))
                self._curves[name] = cached
            if cached is not None:
                curves.append((entry, cached[1]))
        imgui.text_wrapped(f"plane of incidence (light theta = {state.light[0]:.1f} deg); radius = BRDF (1/sr)"
                           + ("; luminance per material" if len(curves) > 1 else ""))
        state.plotted["Polar"] = [entry.name if entry is not None else state.material_path.name for entry, _ in curves]
        if not curves:
            return
        if implot.begin_plot("polar", imgui.ImVec2(-1, -1), implot.Flags_.equal):
            fit = implot.AxisFlags_.auto_fit  # the axes follow the lobes: another material, another light
            implot.setup_axes("", "", fit, fit)
            for entry, (theta, brdf) in curves:
                radians = np.radians(theta)
                if len(curves) == 1:
                    for channel, colour in enumerate(((1, 0.3, 0.3, 1), (0.3, 1, 0.3, 1), (0.4, 0.5, 1, 1))):
                        r = np.clip(brdf[:, channel], 0.0, None)
                        implot.plot_line("RGB"[channel], r * np.sin(radians), r * np.cos(radians), implot.Spec(line_color=imgui.ImVec4(*colour)))
                else:
                    r = np.clip(brdf @ LUMINANCE, 0.0, None)
                    implot.plot_line(f"{entry.name}##{id(entry)}", r * np.sin(radians), r * np.cos(radians),
                                     implot.Spec(line_color=imgui.ImVec4(*entry.colour, 1.0), line_weight=2.0))
            # The incident direction, projected on the plane (x toward phi = 0, as the curve's signed theta).
            reach = max(float(np.clip(brdf, 0.0, None).max()) for _, (_, brdf) in curves)
            xs, ys = data.polar_incident(light, max(reach, 1e-6))
            implot.plot_line("light", xs, ys, implot.Spec(line_color=imgui.ImVec4(1.0, 0.85, 0.2, 1.0), line_weight=2.0))
            implot.end_plot()

    def gl_jobs(self) -> list:
        return [self.scheduler.job(name) for name in self._jobs]
