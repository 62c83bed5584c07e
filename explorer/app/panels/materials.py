"""
The Materials window: the loaded materials (``open A B ...``, File > Open...), as BRDF Explorer lists its
BRDFs: each with its plot colour, Visible (the plots overlay the visible ones), Solo (only this one) and
Close; a click on a name shows that material in the sphere views and the Parameters window.
"""

from __future__ import annotations

from explorer.app.panels.base import Panel, record


class MaterialsPanel(Panel):
    title = "Materials"
    dock = "left_top"

    def draw(self, imgui) -> None:
        state, app = self.state, self.app
        action = None
        for index, entry in enumerate(state.materials):
            imgui.push_id(f"material{index}")
            imgui.color_button("##colour", imgui.ImVec4(*entry.colour, 1.0), imgui.ColorEditFlags_.no_tooltip, imgui.ImVec2(14, 14))
            imgui.same_line()
            _, entry.visible = imgui.checkbox("##visible", entry.visible)
            record(state, f"material:{index}:visible")
            if imgui.is_item_hovered():
                imgui.set_tooltip("Visible: overlaid in the plots")
            imgui.same_line()
            if imgui.small_button("Solo"):
                action = ("solo", index)
            record(state, f"material:{index}:solo")
            imgui.same_line()
            imgui.begin_disabled(len(state.materials) <= 1)
            if imgui.small_button("Close"):
                action = ("close", index)
            imgui.end_disabled()
            record(state, f"material:{index}:close")
            imgui.same_line()
            clicked, _ = imgui.selectable(entry.name, index == state.selected)
            record(state, f"material:{index}")
            if imgui.is_item_hovered():
                imgui.set_tooltip(str(entry.path))
            if clicked:
                action = ("select", index)
            imgui.pop_id()
        if imgui.small_button("Open..."):
            app.dialog.start(state)
        record(state, "materials:open")
        if action is not None:  # after the loop: closing changes the list being drawn
            kind, index = action
            {"solo": app.solo, "close": app.close, "select": app.select}[kind](index)
