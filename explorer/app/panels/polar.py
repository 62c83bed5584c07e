"""The Polar window: the BRDF in the plane of incidence (the scatter view's middle row), of every visible material."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from explorer.rendering import request_view
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
        self._fallback = SimpleNamespace(polar_log=False, polar_normalise=False)  # no material entry (not in the app)

    def _job_name(self, entry) -> str:
        return "polar" if entry is None or entry.material is self.state.material else f"polar:{id(entry.material)}"

    def draw(self, imgui) -> None:
        from imgui_bundle import implot

        from explorer.views.mirror import is_mirror_only, plotted_quantity

        state = self.state
        entries = state.visible_entries() or [None]
        light = light_vector(state.light, state.camera)
        curves, self._jobs = [], []
        for entry in entries:
            name = self._job_name(entry)
            material, values = (state.material, state.values) if entry is None else (entry.material, entry.values)
            job = self.scheduler.job(name)
            request_view(job, material, values, "scatter", (POLAR_SAMPLES, 1), light=light, dragging=False)
            self._jobs.append(name)
            cached = self._curves.get(name)
            if job.complete and (cached is None or cached[0] != job.generation):
                cached = (job.generation, data.polar_curve(job.read()))
                self._curves[name] = cached
            if cached is not None:
                curves.append((entry, material, cached[1]))
        mirrors = [is_mirror_only(material) for _, material, _ in curves]
        # A smooth mirror's "BRDF" is its reflectance R(theta_d) at the half vector: the weight of its Dirac, not a density.
        quantity = plotted_quantity(mirrors)
        imgui.text_wrapped(f"plane of incidence (light theta = {state.light[0]:.1f} deg); radius = {quantity}"
                           + ("; luminance per material" if len(curves) > 1 else ""))
        state.plotted["Polar"] = [entry.name if entry is not None else state.material_path.name for entry, _, _ in curves]
        if not curves:
            return
        self._scales(imgui, [entry for entry, _, _ in curves])
        if any(self._options(entry).polar_log for entry, _, _ in curves):
            imgui.text(f"log: radius = log10(1 + value / {data.POLAR_LOG_FLOOR:g})")
        plotted, report = [], {}
        for (entry, material, (theta, brdf)), mirror in zip(curves, mirrors):
            options = self._options(entry)
            radians = np.radians(theta)
            channels = [brdf[:, c] for c in range(3)] if len(curves) == 1 else [brdf @ LUMINANCE]
            radii = [data.polar_radius(values, options.polar_log, options.polar_normalise) for values in channels]
            plotted.append((entry, [(r * np.sin(radians), r * np.cos(radians)) for r in radii]))
            report[entry.name if entry is not None else state.material_path.name] = {
                "peak": float(max(r.max() for r in radii)), "log": options.polar_log, "normalise": options.polar_normalise,
                "quantity": "reflectance" if mirror else "BRDF"}
        reach = max(max(float(np.hypot(x, y).max()) for x, y in lines) for _, lines in plotted)
        incident = data.polar_incident(light, max(reach, 1e-6))
        limits = data.polar_limits([xy for _, lines in plotted for xy in lines] + [incident])
        state.polar_report = {"curves": report, "limits": list(limits), "quantity": quantity}
        if implot.begin_plot("polar", imgui.ImVec2(-1, -1), implot.Flags_.equal):
            # Axes from the curves themselves (every point inside, square): ImPlot's auto-fit with an equal aspect
            # cut the tallest lobe; they follow another material, light or scale at once.
            implot.setup_axes("", "", 0, 0)
            implot.setup_axes_limits(limits[0], limits[1], limits[2], limits[3], imgui.Cond_.always)
            for entry, lines in plotted:
                if len(lines) == 3:
                    for channel, (xs, ys), colour in zip("RGB", lines, ((1, 0.3, 0.3, 1), (0.3, 1, 0.3, 1), (0.4, 0.5, 1, 1))):
                        implot.plot_line(channel, xs, ys, implot.Spec(line_color=imgui.ImVec4(*colour)))
                else:
                    xs, ys = lines[0]
                    implot.plot_line(f"{entry.name}##{id(entry)}", xs, ys,
                                     implot.Spec(line_color=imgui.ImVec4(*entry.colour, 1.0), line_weight=2.0))
            implot.plot_line("light", *incident, implot.Spec(line_color=imgui.ImVec4(1.0, 0.85, 0.2, 1.0), line_weight=2.0))
            implot.end_plot()

    def _options(self, entry):
        """Where a curve's scale is kept: its material's entry (the shown material's without one)."""
        return entry if entry is not None else self._fallback

    def _scales(self, imgui, entries) -> None:
        """A log and a normalise checkbox per material (recorded as ``polar_log:I``, ``polar_normalise:I``, I its place)."""
        from explorer.app.panels.base import record

        state = self.state
        for index, entry in enumerate(entries):
            options = self._options(entry)
            if len(entries) > 1:
                imgui.text_colored(imgui.ImVec4(*entry.colour, 1.0), entry.name)
                imgui.same_line()
            _, options.polar_log = imgui.checkbox(f"log##polar{index}", options.polar_log)
            record(state, f"polar_log:{index}")
            if imgui.is_item_hovered():
                imgui.set_tooltip(f"log scale, log10(1 + x / {data.POLAR_LOG_FLOOR:g}): the decades above {data.POLAR_LOG_FLOOR:g}; "
                                  "a wide, dim lobe stays visible beside a narrow, bright one")
            imgui.same_line()
            _, options.polar_normalise = imgui.checkbox(f"normalise##polar{index}", options.polar_normalise)
            record(state, f"polar_normalise:{index}")
            if imgui.is_item_hovered():
                imgui.set_tooltip("divide this curve by its own peak: every lobe's shape at the same size")

    def gl_jobs(self) -> list:
        return [self.scheduler.job(name) for name in self._jobs]
