"""The Strips window: Figure 4's θ gradient, one row per method."""

from __future__ import annotations

from explorer.rendering import request_view
from explorer.app import data
from explorer.app.state import has_reflectance
from explorer.app.panels.base import Panel

STRIP_WIDTH = 512


class StripsPanel(Panel):
    title = "Strips"
    dock = "right_bottom"
    gl_order = 2

    def __init__(self, app):
        super().__init__(app)
        self._methods: list = []  # the strips' job names drawn this frame (their views stay in the scheduler)

    def draw(self, imgui) -> None:
        state = self.state
        self._methods = []
        names = data.method_names(state.material)
        if not has_reflectance(state.material):
            imgui.text("this material has no reflectance(cos_theta)")
            return
        if data.has_bragg_spectrum(state.material):
            methods = [m for m in data.BRAGG_STRIP_METHODS if m in names]
        else:
            methods = list(names) or [None]
        imgui.text("theta from 0 deg (left) to 90 deg (right)")
        state.strip_rows = []
        for method in methods:
            values = state.values if method is None else {**state.values, "method": float(method)}
            label = "" if method is None else f"{method} {names.get(method, '')}"
            self._strip(imgui, f"strip{method}", state.material, values, label)
            state.strip_rows.append(label)
        # The other visible materials with a reflectance: one strip each, at their own method, in their colour.
        others = [e for e in state.visible_entries() if e.material is not state.material and has_reflectance(e.material)]
        if others:
            imgui.separator()
        for entry in others:
            method = entry.values.get("method")
            label = entry.name + ("" if method is None else f" ({data.method_names(entry.material).get(int(method), int(method))})")
            self._strip(imgui, f"strip:{id(entry.material)}", entry.material, entry.values, label, entry.colour)
        state.plotted["Strips"] = [state.material_path.name] + [entry.name for entry in others]

    def _strip(self, imgui, name, material, values, label, colour=None) -> None:
        if name not in self._methods:
            self._methods.append(name)
        job = self.scheduler.job(name)
        request_view(job, material, values, "gradient", (STRIP_WIDTH, 1), dragging=self.app.dragging)
        texture = self.scheduler.show(name, (STRIP_WIDTH, 1), job)
        avail = imgui.get_content_region_avail().x
        imgui.image(imgui.ImTextureRef(texture.glo), imgui.ImVec2(max(avail - 110, 32), 22), imgui.ImVec2(0, 1), imgui.ImVec2(1, 0))
        imgui.same_line()
        if colour is None:
            imgui.text(label)
        else:
            imgui.text_colored(imgui.ImVec4(*colour, 1.0), label)

    def gl_jobs(self) -> list:
        return [self.scheduler.job(name) for name in self._methods]
