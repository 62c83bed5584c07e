"""The Sphere window: the material lit (``lit``), in the white furnace (``sphere``) or under the sky (``env``)."""

from __future__ import annotations

from explorer.app.camera import light_vector
from explorer.app.scheduler import model_mesh
from explorer.app.state import ENV_TARGETS, MODES, SPHERE_MODELS, auto_view_size, has_reflectance
from explorer.app.panels.base import Panel, combo, record, show_image
from explorer.rendering import request_view


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
            chosen = combo(state, "##shown", state.material_path.name,
                           [(index, f"{entry.name}##{index}") for index, entry in enumerate(state.materials)],
                           state.selected, "shown", "shown")
            if chosen is not None:
                self.app.select(chosen)
        imgui.new_line()
        if state.mode == "sphere" and not has_reflectance(state.material):
            imgui.text_colored(imgui.ImVec4(1, 0.7, 0.3, 1), "this material has no reflectance(cos_theta): showing lit")
        self._model_and_environment(imgui)
        if state.view_size_auto:  # the sphere fills the window, less its status line
            avail = imgui.get_content_region_avail()
            state.view_size = auto_view_size(avail.x, avail.y - 2.0 * imgui.get_text_line_height_with_spacing())
        size = (state.view_size, state.view_size)
        job = scheduler.job("main")
        # While a slider moves, the tables are built on a worker thread (drafts first): the values shown are the newest ready.
        dragging = self.app.dragging
        values = scheduler.prefetcher.values(state.material, state.values, dragging)
        if state.mode == "env":
            texture = scheduler.show("main", size, scheduler.env.request(state, size, values))
        else:
            view, inputs = state.main_view(), None
            mesh = model_mesh(state.model, scheduler.env.meshes) if view == "lit" else None
            if mesh is not None:  # the mesh's rasterised normals (explorer.gpu.mesh), once per model and size
                from explorer.gpu.mesh import MESH_TEMPLATES, mesh_normals

                if self._normals_key != (state.model, size):
                    self._normals = mesh_normals(scheduler.renderer, mesh, *size)
                    self._normals_key = (state.model, size)
                view, inputs = MESH_TEMPLATES["lit"], {"mesh_normals": self._normals}
            request_view(job, state.material, values, view, size, light=light_vector(state.light, state.camera), dragging=dragging,
                         inputs=inputs, inputs_key=state.model, environment=self._mirror_environment(),
                         uniforms=state.lit_uniforms(state.material, view))
            texture = scheduler.show("main", size, job)
        show_image(state, texture, size, "sphere_image", interactive=True)
        if state.mode == "env":  # the env mode's own progress: samples per pixel, converged at the target
            env = state.env_progress or scheduler.env.progress(state.env_target_spp)
            progress = (f"converged, {env['samples']} samples per pixel" if env["converged"]
                        else f"converging, {env['samples']}/{env['target']} samples per pixel")
        elif job.complete:
            progress = "done"
        elif job.has_preview and job.refined_rows == 0:
            progress = "preview %dx%d" % job.preview_size
        else:
            progress = f"refining {100 * job.progress:.0f}%"
        shown = "env" if state.mode == "env" else state.main_view()
        imgui.text(f"{shown} {size[0]}x{size[1]}: {progress}; {state.frame_label()}")
        if job.error:
            imgui.text_colored(imgui.ImVec4(1.0, 0.35, 0.3, 1.0), job.error)

    _normals_key = None
    _normals = None

    def _mirror_environment(self):
        """What a smooth mirror reflects in the lit mode (the env mode's environment and turn), else None."""
        from explorer.views.mirror import is_mirror_only

        state = self.state
        if state.main_view() != "lit" or not is_mirror_only(state.material):
            return None
        return self.scheduler.env.environment(state.environment).rotated(state.env_rotation)

    def _model_and_environment(self, imgui) -> None:
        """Switch model (the sphere or a mesh), and in the env mode the environment, its turn, backdrop and target."""
        from explorer.views.env import ENVIRONMENTS

        state = self.state
        imgui.set_next_item_width(120)
        state.model = combo(state, "model", state.model, [(n, n) for n in SPHERE_MODELS], state.model, "model", "model_combo") or state.model
        if state.mode == "sphere" and state.model != "sphere":
            imgui.same_line()
            imgui.text_colored(imgui.ImVec4(1, 0.7, 0.3, 1), "(the white furnace shows the sphere)")
        if state.mode != "env" and self._mirror_environment() is None:
            return  # a smooth mirror in the lit mode reflects the environment: its choice and turn, no more
        imgui.set_next_item_width(140)
        state.environment = combo(state, "environment", state.environment, [(n, n) for n in ENVIRONMENTS], state.environment,
                                  "environment", "environment_combo") or state.environment
        if state.mode == "env":
            imgui.same_line()
            _, state.env_background = imgui.checkbox("background", state.env_background)
            record(state, "env_background")
        imgui.set_next_item_width(200)
        changed, turn = imgui.slider_float("probe rotation", state.env_rotation, -180.0, 180.0, "%.0f deg")
        record(state, "env_rotation")
        if changed:
            state.env_rotation = float(turn)
        if state.mode != "env":
            return
        imgui.same_line()
        imgui.set_next_item_width(90)
        targets = [str(t) for t in ENV_TARGETS]
        current = ENV_TARGETS.index(state.env_target_spp) if state.env_target_spp in ENV_TARGETS else 1
        changed, index = imgui.combo("converged at (spp)", current, targets)
        if changed:
            state.env_target_spp = ENV_TARGETS[index]

    def gl_jobs(self) -> list:
        return [self.scheduler.job("main")] if self.state.mode != "env" else []
