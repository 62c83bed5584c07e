"""The Strips window: Figure 4's θ gradient, one row per method."""

from __future__ import annotations

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
        self._methods: list = []  # the methods a strip was requested for (their views stay in the scheduler)

    def draw(self, imgui) -> None:
        state = self.state
        names = data.method_names(state.material)
        if not has_reflectance(state.material):
            imgui.text("this material has no reflectance(cos_theta)")
            return
        if state.material.model in data.BRAGG_MODELS:
            methods = [m for m in data.BRAGG_STRIP_METHODS if m in names]
        else:
            methods = list(names) or [None]
        imgui.text("theta from 0 deg (left) to 90 deg (right)")
        for method in methods:
            if method not in self._methods:
                self._methods.append(method)
            job = self.scheduler.job(f"strip{method}")
            values = state.values if method is None else {**state.values, "method": float(method)}
            job.request(state.material, values, "gradient", (STRIP_WIDTH, 1), dragging=self.app.dragging)
            texture = self.scheduler.show(f"strip{method}", (STRIP_WIDTH, 1), job)
            avail = imgui.get_content_region_avail().x
            label = "" if method is None else f"{method} {names.get(method, '')}"
            imgui.image(imgui.ImTextureRef(texture.glo), imgui.ImVec2(max(avail - 110, 32), 22), imgui.ImVec2(0, 1), imgui.ImVec2(1, 0))
            imgui.same_line()
            imgui.text(label)

    def gl_jobs(self) -> list:
        return [self.scheduler.job(f"strip{method}") for method in self._methods]
