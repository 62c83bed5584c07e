"""
The Compare window: a split sphere of two methods, two parameter sets or two loaded materials (A | B: a
Bragg layer beside BRDF Explorer's ``disney.brdf`` or ``ggx_schlick``), or their ΔE2000 heat-map with its
colour bar.
"""

from __future__ import annotations

import numpy as np

from explorer.rendering import request_view
from explorer.app import data
from explorer.app.camera import light_vector
from explorer.app.panels.base import Panel, combo, record, show_image
from explorer.app.state import has_reflectance

#: The heat-map's colour bar (pixels wide).
COLOUR_BAR_WIDTH = 70


def compare_size(imgui, state, side: float) -> tuple[int, int]:
    """
    The pair's resolution: fitted to the window (less ``side`` pixels, the heat-map's colour bar, and the mean
    line under it) as the sphere's, when the resolution follows the windows; else half the sphere's above 256.
    """
    from explorer.app.state import auto_view_size

    if state.view_size_auto:
        avail = imgui.get_content_region_avail()
        side_px = auto_view_size(avail.x - side, avail.y - 2.0 * imgui.get_text_line_height_with_spacing())
        return side_px, side_px
    return (state.view_size // 2, state.view_size // 2) if state.view_size > 256 else (state.view_size, state.view_size)


class ComparePanel(Panel):
    title = "Compare"
    dock = "centre"
    gl_order = 1

    def __init__(self, app):
        super().__init__(app)
        self._heat_texture = None
        self._heat_generation = None  # the pair of images the heat-map was computed from

    def draw(self, imgui) -> None:
        state, c = self.state, self.state.compare
        _, c.on = imgui.checkbox("compare", c.on)
        record(state, "compare_on")
        names = data.method_names(state.material)
        if imgui.radio_button("two methods", c.kind == "methods") and names:
            c.kind = "methods"
        imgui.same_line()
        if imgui.radio_button("two parameter sets (A = current | B)", c.kind == "sets"):
            c.kind = "sets"
        if imgui.radio_button("two materials (A = shown | B)", c.kind == "materials"):
            c.kind = "materials"
        record(state, "compare_materials")
        if c.kind == "materials":
            others = [i for i in range(len(state.materials)) if i != state.selected]
            if c.material_b not in others:
                c.material_b = others[0] if others else state.selected
            chosen = combo(state, "B (right)", state.materials[c.material_b].name,
                           [(i, f"{state.materials[i].name}##{i}") for i in others], c.material_b, "compare_b", "compare_b")
            if chosen is not None:
                c.material_b = chosen
            if not others:
                imgui.text("(open a second material: File > Open...)")
        elif c.kind == "methods" and names:
            labels = [f"{m}: {n}" for m, n in names.items()]
            keys = list(names)
            _, ia = imgui.combo("A (left)", keys.index(c.a) if c.a in keys else 0, labels)
            _, ib = imgui.combo("B (right)", keys.index(c.b) if c.b in keys else 0, labels)
            c.a, c.b = keys[ia], keys[ib]
        elif imgui.button("B := current parameters"):
            c.values_b = dict(state.values)
        _, c.heat = imgui.checkbox(f"dE2000 heat-map (viridis, 0 to {data.HEAT_MAP_TOP:g})", c.heat)
        record(state, "compare_heat")
        if not c.on:
            imgui.text("(off)")
            return
        size = compare_size(imgui, state, COLOUR_BAR_WIDTH + 8 if c.heat else 0.0)
        c.size = list(size)
        if c.kind == "materials":
            values_a, values_b = state.values, None  # B: the entry's own values, below
        elif c.kind == "methods" and names:
            values_a = {**state.values, "method": float(c.a)}
            values_b = {**state.values, "method": float(c.b)}
        else:
            known = {p.name for p in state.material.parameters}
            values_a, values_b = state.values, state.material.resolve({k: v for k, v in c.values_b.items() if k in known})
        light, dragging, view = light_vector(state.light, state.camera), self.app.dragging, state.main_view()
        material_b = state.material
        if c.kind == "materials":
            entry = state.materials[c.material_b]
            material_b, values_b = entry.material, entry.values
            # Two materials in one view: the sphere's when both have a reflectance, else both lit (every material has a BRDF).
            if not (has_reflectance(state.material) and has_reflectance(material_b)):
                view = "lit"
        a, b = self.scheduler.job("compare_a"), self.scheduler.job("compare_b")
        # What a smooth mirror reflects in the lit view: the Sphere window's environment and probe turn.
        environment = self.scheduler.env.environment(state.environment).rotated(state.env_rotation)
        request_view(a, state.material, values_a, view, size, light=light, dragging=dragging, environment=environment,
                     uniforms=state.lit_uniforms(state.material, view))
        request_view(b, material_b, values_b, view, size, light=light, dragging=dragging, environment=environment,
                     uniforms=state.lit_uniforms(material_b, view))
        if c.heat and self._heat_texture is not None:
            show_image(state, self._heat_texture, size, "compare_image", side=COLOUR_BAR_WIDTH + 8)
            imgui.same_line()
            from imgui_bundle import implot

            shown = state.rects["compare_image"]
            implot.colormap_scale("dE2000", 0.0, data.HEAT_MAP_TOP, imgui.ImVec2(COLOUR_BAR_WIDTH, shown[3] - shown[1]),
                                  "%g", 0, implot.Colormap_.viridis)
            record(state, "compare_colour_bar")
        else:
            show_image(state, self.scheduler.show("compare", size, a, b), size, "compare_image")
        if state.mean_delta_e is not None:
            imgui.text(f"mean dE2000 over the sphere: {state.mean_delta_e:.3f}")
        else:
            imgui.text("mean dE2000: (rendering)")

    def gl_jobs(self) -> list:
        return [self.scheduler.job("compare_a"), self.scheduler.job("compare_b")] if self.state.compare.on else []

    def after_gl(self) -> None:
        """The heat-map and the mean ΔE2000, once both images are complete."""
        a, b = self.scheduler.job("compare_a"), self.scheduler.job("compare_b")
        if not (self.state.compare.on and a.complete and b.complete):
            return
        generation = (a.generation, b.generation)
        if generation == self._heat_generation:
            return
        mask = data.disc_mask(*a.size)
        delta_e, self.state.mean_delta_e = data.delta_e_map(a.read(), b.read(), mask)
        rgba = data.heat_map_rgba(delta_e, data.HEAT_MAP_TOP)
        rgba[~mask] = (0, 0, 0, 255)
        self._heat_texture = self.app.renderer.resources.replace(self._heat_texture, np.ascontiguousarray(rgba[::-1]),
                                                                 dtype="f1", linear=True, origin="ΔE map")
        self._heat_generation = generation
