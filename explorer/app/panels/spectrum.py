"""The Spectrum window: R_s, R_p, their average and envelope at one angle, band gaps, landmarks, boxes (Figure 3)."""

from __future__ import annotations

import time

import numpy as np

from explorer.materials.brd import round_integer
from explorer.app import data
from explorer.app.panels.base import Panel, checkbox_width, flow, record

#: Where the plot's legend is (reported): outside the plot's area, which it never covers.
SPECTRUM_LEGEND = "right of the plot, outside its area"
#: The plot's refresh period while a slider is dragged (seconds).
DRAG_SPECTRUM_S = 0.1


class SpectrumPanel(Panel):
    title = "Spectrum"
    dock = "right_top"

    def __init__(self, app):
        super().__init__(app)
        self._spectrum: data.Spectrum | None = None
        self._key = None  # the values and angle of the spectrum shown (None: its structure is outdated)
        self._time = 0.0
        self._structure: data.Spectrum | None = None  # the last spectrum with its gaps, landmarks and boxes
        self._others: dict = {}  # id(material) -> (key, spectrum) of the other visible materials

    def draw(self, imgui) -> None:
        state = self.state
        others = [e for e in state.visible_entries() if e.material is not state.material and data.has_bragg_spectrum(e.material)]
        if not data.has_bragg_spectrum(state.material) and not others:
            imgui.text("the spectrum needs a Bragg mirror material (n1, n2, Lambda, delta, N)")
            return
        _, state.spectrum_theta = imgui.slider_float("theta", state.spectrum_theta, 0.0, 89.0, "%.1f deg")
        record(state, "spectrum_theta")
        for index, key in enumerate(state.spectrum_show):  # as many on a line as fit: none cut at 1280x800
            if index:
                flow(imgui, checkbox_width(imgui, key))
            _, state.spectrum_show[key] = imgui.checkbox(key, state.spectrum_show[key])
            record(state, f"spectrum_show:{key}")
        selected = state.materials[state.selected] if state.materials else None
        shown = selected is None or (selected.visible and data.has_bragg_spectrum(state.material))
        if shown:
            self._update()
        overlays = [(entry, self._other(entry)) for entry in others]
        state.plotted["Spectrum"] = ([state.material_path.name] if shown else []) + [entry.name for entry in others]
        state.spectrum_legend = SPECTRUM_LEGEND
        self._plot(imgui, self._spectrum if shown else None, state.spectrum_show, overlays,
                   selected.colour if selected is not None and overlays else None)

    def _other(self, entry) -> data.Spectrum:
        """Another visible Bragg material's curves (no structure), cached on its values and the angle."""
        key = (tuple(sorted(entry.values.items())), self.state.spectrum_theta)
        cached = self._others.get(id(entry.material))
        if cached is None or cached[0] != key:
            cached = (key, data.spectrum(entry.values, self.state.spectrum_theta, structure=False))
            self._others[id(entry.material)] = cached
        return cached[1]

    def _update(self) -> None:
        state, dragging = self.state, self.app.dragging
        key = (tuple(sorted(state.values.items())), state.spectrum_theta)
        # While a slider is dragged the curves follow at most every DRAG_SPECTRUM_S (their ~3 ms of numpy
        # would otherwise come out of every frame of the sphere's); on release they catch up at once.
        throttled = dragging and time.perf_counter() - self._time < DRAG_SPECTRUM_S
        if key == self._key or (throttled and self._spectrum is not None):
            return
        self._time = time.perf_counter()
        structure = not dragging
        method = round_integer(state.values.get("method", 0))
        s = round_integer(state.values.get("s", 3))
        self._spectrum = data.spectrum(state.values, state.spectrum_theta, method, s, structure=structure)
        if not structure and self._structure is not None:
            old = self._structure
            self._spectrum.gaps, self._spectrum.landmarks, self._spectrum.boxes = old.gaps, old.landmarks, old.boxes
        self._key = key if structure else None
        if structure:
            self._structure = self._spectrum

    @staticmethod
    def _plot(imgui, sp: data.Spectrum | None, show: dict, overlays=(), colour=None) -> None:
        """The selected material's curves (``sp``; its average in ``colour`` beside others), then each overlay's average."""
        from imgui_bundle import implot

        if not implot.begin_plot("R(lambda)", imgui.ImVec2(-1, -1)):
            return
        implot.setup_axes("wavelength (nm)", "reflectance")
        implot.setup_axes_limits(360, 830, 0, 1.05)
        # The legend right of the plot: inside, it covered the short-wavelength end (a band near 420 nm); in a row
        # above, a narrow window cut its last entries.
        implot.setup_legend(implot.Location_.east, implot.LegendFlags_.outside)
        for entry, other in overlays:
            implot.plot_line(f"{entry.name} average##{id(entry)}", other.wavelengths, 0.5 * (other.R["s"] + other.R["p"]),
                             implot.Spec(line_color=imgui.ImVec4(*entry.colour, 1.0), line_weight=2.0))
        if sp is None:
            implot.end_plot()
            return
        if show["gaps"]:
            for low, high in sp.gaps:
                xs = np.array([low, high])
                implot.plot_shaded("band gaps", xs, np.array([1.05, 1.05]), 0.0, implot.Spec(fill_color=imgui.ImVec4(0.5, 0.5, 0.5, 0.25)))
        if show["landmarks"] and sp.landmarks.size:
            implot.plot_inf_lines("landmarks", sp.landmarks.astype(np.float64), implot.Spec(line_color=imgui.ImVec4(0.6, 0.6, 0.6, 0.6)))
        average = 0.5 * (sp.R["s"] + sp.R["p"])
        if show["s"]:
            implot.plot_line("R_s", sp.wavelengths, sp.R["s"])
        if show["p"]:
            implot.plot_line("R_p", sp.wavelengths, sp.R["p"])
        if show["average"]:
            spec = implot.Spec(line_weight=2.0) if colour is None else implot.Spec(line_weight=2.0, line_color=imgui.ImVec4(*colour, 1.0))
            implot.plot_line("average", sp.wavelengths, average, spec)
        if show["envelope"]:
            implot.plot_line("envelope", sp.wavelengths, 0.5 * (sp.envelope["s"] + sp.envelope["p"]))
        if show["boxes"]:
            for polarisation, boxes in sp.boxes.items():
                xs, ys = data.boxes_polyline(boxes)
                if xs.size:
                    implot.plot_line(f"boxes {polarisation}", xs, ys)
        implot.end_plot()
