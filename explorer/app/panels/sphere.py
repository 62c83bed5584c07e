"""The Sphere window: the material lit (``lit``), in the white furnace (``sphere``) or under the sky (``env``)."""

from __future__ import annotations

from explorer.app.camera import light_vector
from explorer.app.state import MODES, has_reflectance
from explorer.app.panels.base import Panel, record, show_image


class SpherePanel(Panel):
    title = "Sphere"
    dock = "centre"
    gl_order = 0

    def draw(self, imgui) -> None:
        state, scheduler = self.state, self.scheduler
        for mode in MODES:
            if imgui.radio_button(mode, state.mode == mode):
                state.mode = mode
            record(state, f"mode:{mode}")
            imgui.same_line()
        imgui.new_line()
        if state.mode == "sphere" and not has_reflectance(state.material):
            imgui.text_colored(imgui.ImVec4(1, 0.7, 0.3, 1), "this material has no reflectance(cos_theta): showing lit")
        size = (state.view_size, state.view_size)
        job = scheduler.job("main")
        # While a slider moves, the tables are built on a worker thread (drafts first): the values shown are the newest ready.
        dragging = self.app.dragging
        values = scheduler.prefetcher.values(state.material, state.values, dragging)
        if state.mode == "env":
            texture = scheduler.show("main", size, scheduler.env.request(state, size, values))
        else:
            job.request(state.material, values, state.main_view(), size, light=light_vector(state.light, state.camera), dragging=dragging)
            texture = scheduler.show("main", size, job)
        show_image(state, texture, size, "sphere_image", interactive=True)
        if job.complete:
            progress = "done"
        elif job.has_preview and job.refined_rows == 0:
            progress = "preview %dx%d" % job.preview_size
        else:
            progress = f"refining {100 * job.progress:.0f}%"
        imgui.text(f"{state.main_view()} {size[0]}x{size[1]}: {progress}; {state.frame_label()}")
        if job.error:
            imgui.text_colored(imgui.ImVec4(1.0, 0.35, 0.3, 1.0), job.error)

    def gl_jobs(self) -> list:
        return [self.scheduler.job("main")] if self.state.mode != "env" else []
