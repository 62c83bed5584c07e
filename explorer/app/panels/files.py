"""The Files window: parameter sets (JSON or BRDF Explorer's ``.bparam``), another material, a screenshot."""

from __future__ import annotations

from pathlib import Path

from explorer.errors import LocatedError
from explorer.app.parameter_files import load_values, save_values
from explorer.app.screenshots import screenshot_name
from explorer.app.panels.base import Panel, record
from explorer.app.state import MODES


class FilesPanel(Panel):
    title = "Files"
    dock = "left"

    def draw(self, imgui) -> None:
        state = self.state
        imgui.text_wrapped("Parameter sets: .json, or BRDF Explorer's .bparam. Materials: .brd / .brdf.")
        _, state.file_path = imgui.input_text("path", state.file_path)
        if imgui.button("Save parameters"):  # and the view: light, camera, exposure, view, environment
            try:
                save_values(state.file_path, state.material, state.values, state.view_settings())  # render --params shows this view
                state.status = f"saved {state.file_path}"
            except LocatedError as error:
                state.status = str(error)
        record(state, "save_parameters")
        imgui.same_line()
        if imgui.button("Load parameters"):
            try:
                loaded = load_values(state.file_path, state.material)
                state.values = state.material.resolve({**state.values, **loaded.values})
                apply_view(state, loaded.view)
                state.status = f"loaded {state.file_path}" + (f"; skipped {', '.join(loaded.skipped)}" if loaded.skipped else "")
            except LocatedError as error:
                state.status = str(error)
        if imgui.button("Open material"):
            self.app.reload(Path(state.file_path))
        record(state, "open_material")
        imgui.same_line()
        if imgui.button("Screenshot (F12)"):
            state.pending_screenshot = screenshot_name(state)
        if state.status:
            imgui.text_wrapped(state.status)


def apply_view(state, view: dict | None) -> None:
    """A parameter set's saved view onto the app (its light, camera, exposure and sphere mode)."""
    if not view:
        return
    if "light" in view:
        state.light = list(view["light"])
    if "camera" in view:
        state.camera = list(view["camera"])
    if "exposure" in view:
        state.exposure = float(view["exposure"])
    if "tonemap" in view:
        state.tonemap = view["tonemap"]
    if "fill" in view:
        state.fill = float(view["fill"])
    if view.get("view") in MODES:
        state.mode = view["view"]
