"""The Parameters window: a widget per material parameter, the presets, light, camera, exposure, resolution."""

from __future__ import annotations

from explorer.errors import LocatedError
from explorer.materials.brd import round_integer
from explorer.materials.media import MEDIA, medium_labels
from explorer.materials.methods import method_labels
from explorer.app.parameter_files import inactive_parameters, slider_format, widget_kind
from explorer.app.state import VIEW_SIZES
from explorer.app.badge import BadgeWorker
from explorer.app.panels.base import Panel, combo, record


def parameter_tooltip(parameter) -> str:
    """A slider's tooltip: the parameter's meaning and unit (its ``.brd`` line's comment), its range and default."""
    bounds = "" if parameter.min is None else f" in [{parameter.min:g}, {parameter.max:g}]"
    unit = f" {parameter.unit}" if parameter.unit and parameter.unit != "1" else ""
    meaning = f"{parameter.doc}\n" if parameter.doc else ""
    return f"{meaning}{parameter.name}: {parameter.type}{bounds}{unit}, default {parameter.default}; Ctrl-click resets"


class ParametersPanel(Panel):
    title = "Parameters"
    dock = "left"

    def __init__(self, app):
        super().__init__(app)
        self.badge = BadgeWorker()

    def draw(self, imgui) -> None:
        state, app = self.state, self.app
        imgui.text_wrapped(_shown_path(state.material_path))
        reload_clicked = imgui.button("Reload (F5)")
        record(state, "reload")
        if reload_clicked:
            app.reload()
        if state.error:
            imgui.push_text_wrap_pos(0.0)
            imgui.text_colored(imgui.ImVec4(1.0, 0.35, 0.3, 1.0), state.error)
            imgui.pop_text_wrap_pos()
        presets = app.presets()
        if presets:
            chosen = combo(state, "Preset", state.preset or "(none)", [(n, n) for n in presets], state.preset, "preset", "preset_combo")
            if chosen is not None:
                app.apply_preset(chosen)
        imgui.separator()
        io = imgui.get_io()
        inactive = inactive_parameters(state.material, state.values)
        for parameter in state.material.parameters:
            imgui.begin_disabled(parameter.name in inactive)  # a stack's layers beyond its `layers`
            self._parameter_widget(imgui, io, parameter)
            imgui.end_disabled()
        self._accuracy_badge(imgui)
        imgui.separator()
        self._light_and_camera(imgui)
        imgui.separator()
        changed, exposure = imgui.slider_float("exposure", state.exposure, 0.05, 20.0, "%.2f", imgui.SliderFlags_.logarithmic)
        record(state, "exposure")
        if changed:
            state.exposure = exposure
        if state.mode == "lit" and state.lit_uniforms(state.material, state.main_view()):  # not a mirror: it reflects the sky
            changed, fill = imgui.slider_float("environment fill", state.fill, 0.0, 1.0, "%.2f")
            record(state, "fill")
            if changed:
                state.fill = fill
            if imgui.is_item_hovered():
                imgui.set_tooltip("lit view: the radiance of a uniform white environment beside the point light (its colour is "
                                  "the material's albedo); 0: the light alone")
        from explorer.views.tonemap import TONEMAPS

        shown = state.tonemap_for("env" if state.mode == "env" else state.main_view())
        labels = {"auto": f"auto ({shown})", "none": "none (clamp)", "agx": "AgX", "aces": "ACES (Narkowicz)"}
        imgui.set_next_item_width(min(imgui.get_content_region_avail().x * 0.5, 160.0))
        chosen = combo(state, "tone map", labels[state.tonemap], [(k, labels[k]) for k in ("auto", *TONEMAPS)], state.tonemap,
                       "tonemap", "tonemap_combo")
        if chosen is not None:
            state.tonemap = chosen
        if imgui.is_item_hovered():
            imgui.set_tooltip("The display curve after the exposure (sphere, Compare, F12's PNG): AgX rolls vivid colours and "
                              "highlights off to white; none clamps. Auto: AgX for lit and env, none for the colour views.")
        _, state.gamut = imgui.checkbox("gamut overlay (outside sRGB)", state.gamut)
        if imgui.is_item_hovered():
            imgui.set_tooltip("hatch the colours outside sRGB (a negative channel, or above white), judged before the tone map")
        sizes = ["fit the window"] + [str(s) for s in VIEW_SIZES]
        current = 0 if state.view_size_auto else 1 + (VIEW_SIZES.index(state.view_size) if state.view_size in VIEW_SIZES else 2)
        changed, index = imgui.combo("resolution", current, sizes)
        if changed:
            state.view_size_auto = index == 0
            if index > 0:
                state.view_size = VIEW_SIZES[index - 1]
        imgui.text(state.frame_label())
        if state.status:
            imgui.text_wrapped(state.status)

    def _accuracy_badge(self, imgui) -> None:
        """A Bragg mirror's method against the converged table (explorer.materials.accuracy), when it has one."""
        state = self.state
        badge, current = self.badge.request(state.material, state.values, bool(self.app.dragging))
        if badge is None:
            state.accuracy = self.badge.error
            if self.badge.error:
                imgui.text_wrapped(self.badge.error)
            return
        text = badge.text() + ("" if current else " (updating)")
        colour = imgui.ImVec4(0.45, 0.9, 0.45, 1.0) if badge.accurate else imgui.ImVec4(1.0, 0.65, 0.2, 1.0)
        imgui.push_text_wrap_pos(0.0)
        imgui.text_colored(colour, f"method {badge.current.label()}: {text}")
        imgui.pop_text_wrap_pos()
        record(state, "accuracy_badge")
        state.accuracy = f"method {badge.current.label()}: {text}"

    def _light_and_camera(self, imgui) -> None:
        state = self.state
        imgui.text("Light and camera")
        changed, theta = imgui.slider_float("light theta", state.light[0], 0.0, 180.0, "%.1f deg")
        if changed:
            state.light[0] = theta
        changed, phi = imgui.slider_float("light phi", state.light[1], -180.0, 180.0, "%.1f deg")
        if changed:
            state.light[1] = phi
        changed, yaw = imgui.slider_float("camera yaw", state.camera[0], -180.0, 180.0, "%.1f deg")
        if changed:
            state.camera[0] = yaw
        changed, pitch = imgui.slider_float("camera pitch", state.camera[1], -89.0, 89.0, "%.1f deg")
        if changed:
            state.camera[1] = pitch
        changed, zoom = imgui.slider_float("zoom", state.zoom, 1.0, 8.0, "%.2fx")
        if changed:
            state.zoom = zoom
        if imgui.button("Reset camera"):
            state.camera, state.zoom = [0.0, 0.0], 1.0

    def _parameter_widget(self, imgui, io, parameter) -> None:
        """A parameter's widget: slider (integer or float), checkbox or colour editor, plus a typed field."""
        state = self.state
        name, kind = parameter.name, widget_kind(parameter)
        value = state.values[name]
        new = value
        imgui.push_id(name)
        no_ctrl_input = imgui.SliderFlags_.no_input  # Ctrl-click resets instead of typing; the field types
        labels = method_labels(state.material) if name == "method" else {}
        if name.startswith("medium_") and kind == "int":  # the media by name beside the index's slider
            index = name[len("medium_"):]
            media = medium_labels(state.values, name)
            imgui.set_next_item_width(imgui.get_content_region_avail().x * 0.75)
            current = round_integer(value)
            chosen = None
            if imgui.begin_combo(f"{index} medium", media.get(current, str(current))):
                for key, label in media.items():
                    clicked, _ = imgui.selectable(label, key == current)
                    record(state, f"{name}:{key}")
                    if clicked:
                        chosen = key
                imgui.end_combo()
            record(state, f"param:{name}")
            if imgui.is_item_hovered():
                imgui.set_tooltip(parameter_tooltip(parameter))
            imgui.pop_id()
            if chosen is not None and chosen != current:
                # A library medium sets the index's slider to its n at 550 nm too (Material.resolve, n2=chitin).
                update = {index: media[chosen], name: float(chosen)} if 1 <= chosen <= len(MEDIA) else {name: float(chosen)}
                try:
                    state.values = state.material.resolve({**state.values, **update})
                    state.preset = None
                except LocatedError as error:  # an absorbing host: the one-line reason
                    state.status = str(error)
            return
        if labels:  # the methods by name (explorer.materials.methods), not a bare integer slider
            imgui.set_next_item_width(imgui.get_content_region_avail().x * 0.75)
            current = round_integer(value)
            if imgui.begin_combo(name, labels.get(current, str(current))):
                for key, label in labels.items():
                    clicked, _ = imgui.selectable(label, key == current)
                    record(state, f"method:{key}")
                    if clicked:
                        new = float(key)
                imgui.end_combo()
        elif kind == "int":
            imgui.set_next_item_width(imgui.get_content_region_avail().x * 0.55)
            changed, v = imgui.slider_int(name, round_integer(value), int(parameter.min), int(parameter.max), "%d", no_ctrl_input)
            if changed:
                new = float(v)
        elif kind == "float":
            imgui.set_next_item_width(imgui.get_content_region_avail().x * 0.55)
            changed, v = imgui.slider_float(name, float(value), float(parameter.min), float(parameter.max), slider_format(parameter), no_ctrl_input)
            if changed:
                new = float(v)
        elif kind == "bool":
            changed, v = imgui.checkbox(name, bool(value))
            if changed:
                new = bool(v)
        else:
            changed, v = imgui.color_edit3(name, list(value), imgui.ColorEditFlags_.float | imgui.ColorEditFlags_.hdr)
            if changed:  # within the colour's declared range, as a slider keeps a float within its own
                new = tuple(min(max(float(c), parameter.min), parameter.max) for c in v)
        record(state, f"param:{name}")
        if imgui.is_item_clicked() and io.key_ctrl:
            new = parameter.default
        if imgui.is_item_hovered():
            imgui.set_tooltip(parameter_tooltip(parameter))
        if kind in ("int", "float") and not labels:
            imgui.same_line()
            imgui.set_next_item_width(-1)
            typed, text = imgui.input_text("##typed", f"{float(new):g}", imgui.InputTextFlags_.enter_returns_true | imgui.InputTextFlags_.chars_scientific)
            record(state, f"typed:{name}")
            if typed:
                try:
                    new = parameter.coerce(text)
                    state.status = ""
                except ValueError as error:
                    state.status = f"{name}: {error}"
        imgui.pop_id()
        if new != value:
            try:  # the typed values every consumer reads (Material.resolve), the widget's range checked again
                state.values = state.material.resolve({**state.values, name: new})
                state.preset = None
            except LocatedError as error:
                state.status = str(error)


def _shown_path(path) -> str:
    """The material's path as a user would type it: relative to the working directory when inside it."""
    from pathlib import Path

    path = Path(path)
    try:
        return str(path.resolve().relative_to(Path.cwd().resolve()))
    except (ValueError, OSError):
        return str(path)
