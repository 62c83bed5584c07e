"""The Sphere window: the material lit (``lit``), in the white furnace (``sphere``) or under the sky (``env``)."""

from __future__ import annotations

from explorer.app.camera import light_vector
from explorer.app.state import MODES, auto_view_size, has_reflectance
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
        if len(state.materials) > 1:  # which loaded material the sphere shows (as a click in the Materials list)
            imgui.set_next_item_width(min(imgui.get_content_region_avail().x, 220.0))
            if imgui.begin_combo("##shown", state.material_path.name):
                for index, entry in enumerate(state.materials):
                    clicked, _ = imgui.selectable(f"{entry.name}##{index}", index == state.selected)
                    record(state, f"shown:{index}")
                    if clicked:
                        self.app.select(index)
                imgui.end_combo()
            record(state, "shown")
        imgui.new_line()
        if state.mode == "sphere" and not has_reflectance(state.material):
            imgui.text_colored(imgui.ImVec4(1, 0.7, 0.3, 1), "this material has no reflectance(cos_theta): showing lit")
        if state.view_size_auto:  # the sphere fills the window, less its status line
            avail = imgui.get_content_region_avail()
            state.view_size = auto_view_size(avail.x, avail.y - 2.0 * imgui.get_text_line_height_with_spacing())
        size = (state.view_size, state.view_size)
        job = scheduler.job("main")
        if state.mode == "env":
            texture = scheduler.show("main", size, scheduler.env.request(state, size))
        else:
            dragging = self.app.dragging
            values = scheduler.prefetcher.values(state.material, state.values, dragging)
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
