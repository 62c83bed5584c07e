"""
The interactive explorer (issue #4): a glfw window, Dear ImGui and ImPlot (``imgui-bundle``), moderngl.

``bragg-explorer`` (no argument, with a display) opens it on the default Bragg mirror;
``bragg-explorer open FILE.brd|FILE.brdf [--preset NAME]`` on another material. Its images are the
headless renderer's views (:mod:`explorer.app_views`: the same programs, bindings and templates),
drawn progressively into offscreen textures shown in docked ImGui windows:

* **Sphere**: ``lit`` (one directional light; orbit camera by left-drag, light by right-drag or the
  sliders, zoom by the wheel), ``sphere`` (white furnace; the mirror's reflectance) or ``env``
  (progressive Monte Carlo under the default sky, :mod:`explorer.env`);
* **Compare**: a split sphere of two methods or two parameter sets (A | B), or their ΔE2000 heat-map;
* **Strips**: Figure 4's θ gradient, one row per method; **Spectrum**: R_λ at one angle (Figure 3);
  **Polar**: the BRDF in the plane of incidence; **Slice** and **Scatter**: BRDF Explorer's views.

Sliders are generated from the material's parameters (:mod:`explorer.app_params`); Ctrl-click resets
one to its default, the field beside it takes typed values. ``--script FILE`` runs a scripted session
(synthesised mouse input through ImGui's IO, exactly what the glfw callbacks feed it) and ``--report``
writes what happened (frame times, values, screenshots) as JSON: the tests and ``bench --app`` use them.
"""

from __future__ import annotations

import json
import os
import re
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from . import app_data
from .app_params import ParameterFileError, load_values, save_values, slider_format, widget_kind
from .brd import Material, MaterialError, load_material, round_integer
from .errors import LocatedError

DEFAULT_WINDOW = (1280, 800)
VIEW_SIZES = (128, 256, 512, 1024)
DEFAULT_VIEW_SIZE = 512
SIDE_VIEW_SIZE = 256
STRIP_WIDTH = 512
POLAR_SAMPLES = 181
SCREENSHOT_DIR = Path("screenshots")
MODES = ("lit", "sphere", "env")
#: GL budgets (ms) per frame while a slider is dragged: the active view, and each of the others.
DRAG_BUDGET_MS = 16.0
SIDE_DRAG_BUDGET_MS = 0.0
#: The spectrum plot's refresh period while a slider is dragged (seconds).
DRAG_SPECTRUM_S = 0.1


class AppError(Exception):
    """The app cannot start (no display, no OpenGL 3.3 window): a one-line message."""


def display_available() -> bool:
    """Whether a window can be opened: an X11 or Wayland display is named and glfw initialises."""
    if not (os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")):
        return False
    try:
        import glfw
    except ImportError:
        return False
    try:
        ok = glfw.init()
    except Exception:  # glfw raises its own errors on a broken display
        return False
    return bool(ok)


def _initial_values(material: Material, preset: str | None, is_default: bool) -> tuple[dict, str | None]:
    """The values the app starts with: defaults, the default material's tabulated method, a preset."""
    overrides: dict = {}
    if is_default and any(p.name == "method" for p in material.parameters):
        overrides["method"] = 3  # the default material opens on its fastest exact method
    if preset is not None:
        from .presets import presets_for

        overrides.update(presets_for(material.path).get(preset).values)
    return material.resolve(overrides), preset


@dataclass
class ScriptState:
    """A scripted session: actions, the mouse they drive, and the frames they are in."""

    actions: list
    index: int = 0
    frame_in_action: int = 0
    mark: str | None = None
    mouse: tuple[float, float] = (-1.0, -1.0)
    waited: int = 0
    log: list = field(default_factory=list)


class App:
    """
    The explorer window. ``run()`` returns when it is closed (or the script quits).

    Parameters
    ----------
    material_path : path of the ``.brd`` / ``.brdf`` file.
    preset : a preset of that material to start from.
    script, report : a scripted session (a list of actions, see :meth:`_script_step`) and where to
        write its JSON report.
    window_size : the window's size in pixels.
    """

    def __init__(self, material_path, preset: str | None = None, *, script: list | None = None,
                 report: str | os.PathLike | None = None, window_size=DEFAULT_WINDOW, view_size: int = DEFAULT_VIEW_SIZE,
                 is_default: bool = False):
        self.material_path = Path(material_path)
        self.material = load_material(self.material_path)
        self.values, self.preset = _initial_values(self.material, preset, is_default)
        self.script = ScriptState(list(script)) if script is not None else None
        self.report_path = Path(report) if report else None
        self.window_size = tuple(window_size)
        self.view_size = int(view_size)
        self.mode = "sphere" if self._has_reflectance(self.material) else "lit"
        self.light = [45.0, 0.0]  # theta, phi in degrees (explorer.views.geometry.DEFAULT_LIGHT)
        self.camera = [0.0, 0.0]  # yaw, pitch in degrees: rotates the light relative to the view
        self.zoom = 1.0
        self.exposure = 1.0
        self.gamut = False
        self.compare = {"on": False, "kind": "methods", "a": 0, "b": 4, "heat": False, "values_b": dict(self.values)}
        self.mean_delta_e: float | None = None
        self.spectrum_theta = 0.0
        self.spectrum_show = {"s": True, "p": True, "average": True, "envelope": True, "gaps": True, "landmarks": True, "boxes": True}
        self.file_path = "params.json"
        self.status = ""
        self.error = ""  # the material's load/compile error, shown in red; the last good shader stays
        self.rects: dict[str, tuple[float, float, float, float]] = {}
        self.frame_times: list[dict] = []
        self.screenshots: list[str] = []
        self.screenshot_info: dict[str, dict] = {}  # per screenshot: material, view, values, env samples per pixel
        self._pending_screenshot: str | None = None
        self._spectrum = None
        self._spectrum_key = None
        self._spectrum_time = 0.0
        self._spectrum_structure_key = None
        self._polar = None
        self._polar_generation = -1
        self._heat = None
        self._heat_texture = None
        self._heat_generation = None
        self._orbit_drag = False
        self._layout_done = False
        self._quit = False
        self.env = None  # progressive environment render (explorer.env), when that module exists

    # -- material --------------------------------------------------------------------------------

    @staticmethod
    def _has_reflectance(material: Material) -> bool:
        """Whether the material defines ``reflectance(cos_theta)`` (the sphere and gradient views need it)."""
        return re.search(r"\bvec3\s+reflectance\s*\(", material.shader) is not None

    def presets(self) -> dict:
        """The presets of the open material (``{}`` when it has none)."""
        from .presets import PresetError, presets_for

        key = (str(self.material.path), id(self.material))
        if getattr(self, "_presets_key", None) != key:  # read once per material, not every frame
            try:
                self._presets = presets_for(self.material.path).presets
            except PresetError:
                self._presets = {}
            self._presets_key = key
        return self._presets

    def apply_preset(self, name: str) -> None:
        preset = self.presets()[name]
        self.values = self.material.resolve({**{k: v for k, v in self.values.items()}, **preset.values})
        self.preset = name
        self.status = f"preset {name}: {preset.description}"

    def reload(self, path: Path | None = None) -> bool:
        """Read the material from disk again (or ``path``); on any error keep the last good one."""
        path = Path(path) if path is not None else self.material_path
        try:
            material = load_material(path)
            kept = {k: v for k, v in self.values.items() if any(p.name == k for p in material.parameters)}
            values = {}
            for name, value in kept.items():
                try:
                    values[name] = material.parameter(name).coerce(value)
                except ValueError:
                    pass
            values = material.resolve(values)
            view = self.mode if self.mode != "env" else "lit"
            if view == "sphere" and not self._has_reflectance(material):
                view = "lit"
            self.renderer.program(material, view, values)  # compile now: a broken shader is reported here
        except LocatedError as error:
            self.error = str(error)
            return False
        self.material, self.material_path, self.values = material, path, values
        # Nothing of the previous material's values may reach the new one's uniforms: the compare view's
        # set B (its ranges may differ: thin_film's method 5 is no mirror method) and the values shown
        # while a slider drags (see _prepared_values). The env render follows the material (_request_env).
        self.compare["values_b"] = dict(values)
        self._ready_values = None
        # The mode stays as chosen: a material without reflectance() is shown lit in the sphere mode
        # (_main_view) and the next one that has it is shown in the sphere again.
        self.error = ""
        self.status = f"loaded {path}"
        return True

    # -- window ------------------------------------------------------------------------------------

    def _open_window(self):
        import glfw

        if not glfw.init():
            raise AppError("no display: glfw cannot initialise (is DISPLAY set?)")
        glfw.window_hint(glfw.CONTEXT_VERSION_MAJOR, 3)
        glfw.window_hint(glfw.CONTEXT_VERSION_MINOR, 3)
        glfw.window_hint(glfw.OPENGL_PROFILE, glfw.OPENGL_CORE_PROFILE)
        glfw.window_hint(glfw.OPENGL_FORWARD_COMPAT, True)
        window = glfw.create_window(self.window_size[0], self.window_size[1], f"bragg-explorer — {self.material_path.name}", None, None)
        if not window:
            glfw.terminate()
            raise AppError("cannot open an OpenGL 3.3 window on this display")
        glfw.make_context_current(window)
        glfw.swap_interval(0)
        return window

    def run(self) -> int:
        """Open the window and loop until it is closed; returns the exit status."""
        import glfw
        import moderngl
        from imgui_bundle import imgui, implot
        from imgui_bundle.python_backends.glfw_backend import GlfwRenderer

        from .app_views import CostModel, DisplayPass, ProgressiveView
        from .gl import Renderer

        window = self._open_window()
        try:
            self.ctx = moderngl.create_context(require=330)
            self.renderer = Renderer(self.ctx)
            imgui.create_context()
            implot.create_context()
            io = imgui.get_io()
            io.config_flags |= imgui.ConfigFlags_.docking_enable
            io.set_ini_filename(None)  # the layout is built here, the same every time
            self._style(imgui)
            backend = GlfwRenderer(window)
            self.costs = CostModel()
            self.display = DisplayPass(self.ctx)
            self.jobs = {name: ProgressiveView(self.renderer, self.costs) for name in ("main", "compare_a", "compare_b", "slice", "scatter", "polar")}
            self.strip_jobs: dict[int, ProgressiveView] = {}
            self._make_env()
            last = time.perf_counter()
            while not glfw.window_should_close(window) and not self._quit:
                start = time.perf_counter()
                glfw.poll_events()
                if self.script is not None:
                    self._script_step(io)
                backend.process_inputs()
                imgui.new_frame()
                self._ui()
                ui_done = time.perf_counter()
                gl_ms = self._gl_work()
                self.ctx.screen.use()
                self.ctx.clear(0.08, 0.08, 0.09)
                imgui.render()
                backend.render(imgui.get_draw_data())
                drawn = time.perf_counter()
                if self._pending_window_shot:
                    self._window_shot()
                glfw.swap_buffers(window)
                self._take_screenshot()
                now = time.perf_counter()
                values_key = tuple(sorted((k, str(v)) for k, v in self.values.items()))
                changed, self._last_values_key = values_key != getattr(self, "_last_values_key", None), values_key
                self.frame_times.append({
                    "changed": changed,
                    "ms": (now - last) * 1e3, "work_ms": (now - start) * 1e3, "gl_ms": gl_ms,
                    "ui_ms": (ui_done - start) * 1e3, "imgui_draw_ms": (drawn - ui_done) * 1e3 - gl_ms, "swap_ms": (now - drawn) * 1e3,
                    "dragging": self._dragging, "mark": self.script.mark if self.script else None,
                    "main": {"size": list(self.jobs["main"].size), "preview": list(self.jobs["main"].preview_size),
                             "has_preview": self.jobs["main"].has_preview, "complete": self.jobs["main"].complete,
                             "generation": self.jobs["main"].generation},
                    "table_ms": self.renderer.last_table_ms,
                })
                self.last_frame_ms = (now - last) * 1e3
                last = now
            if self._executor is not None:
                self._executor.shutdown(wait=True)
            backend.shutdown()
            implot.destroy_context()
            imgui.destroy_context()
        finally:
            glfw.destroy_window(window)
            glfw.terminate()
            self._write_report()
        return 0

    @staticmethod
    def _style(imgui) -> None:
        """
        Dark style whose window backgrounds are not drawn: the frame's clear colour shows through. On
        a software rasteriser every ImGui pixel is a textured, blended fragment (~40 ns each on llvmpipe),
        and two window-sized background layers alone cost more than a 30 fps frame. ImGui skips
        fully transparent rectangles.
        """
        imgui.style_colors_dark()
        style = imgui.get_style()
        for colour in (imgui.Col_.window_bg, imgui.Col_.child_bg, imgui.Col_.docking_empty_bg):
            style.set_color_(colour, imgui.ImVec4(0.0, 0.0, 0.0, 0.0))
        style.window_rounding = 0.0
        from imgui_bundle import implot

        implot_style = implot.get_style()
        for colour in (implot.Col_.frame_bg, implot.Col_.plot_bg):
            implot_style.set_color_(colour, imgui.ImVec4(0.0, 0.0, 0.0, 0.0))

    def _write_report(self) -> None:
        if self.report_path is None:
            return
        report = {
            "material": str(self.material_path), "values": {k: list(v) if isinstance(v, tuple) else v for k, v in self.values.items()},
            "preset": self.preset, "mode": self.mode, "light": self.light, "camera": self.camera, "view_size": self.view_size,
            "exposure": self.exposure, "frames": self.frame_times, "screenshots": self.screenshots,
            "screenshot_info": self.screenshot_info, "error": self.error,
            "status": self.status, "script_log": self.script.log if self.script else [],
            "mean_delta_e": self.mean_delta_e,
        }
        self.report_path.write_text(json.dumps(report, indent=1))

    # -- scripted sessions -------------------------------------------------------------------------

    def _target_point(self, label: str, fraction: float = 0.5) -> tuple[float, float] | None:
        rect = self.rects.get(label)
        if rect is None:
            return None
        x0, y0, x1, y1 = rect
        return x0 + fraction * (x1 - x0), 0.5 * (y0 + y1)

    def _script_step(self, io) -> None:
        """
        Feed one frame of the script to ImGui's IO. Actions (dicts):

        ``{"wait": N}`` frames; ``{"wait_complete": true}`` until the active view is fully refined;
        ``{"drag": LABEL, "from": F0, "to": F1, "frames": N}`` press at fraction F0 of the item's width,
        move to F1 over N frames, release (sliders are labelled ``param:NAME``);
        ``{"click": LABEL}`` (``preset_combo``, ``preset:NAME``, ``mode:lit``, ...);
        ``{"set": {NAME: VALUE}}`` (bench only: no UI); ``{"mark": TEXT}`` tags the following frames;
        ``{"screenshot": PATH}`` the active view (waits until complete; in ``env``, until a whole sample);
        ``{"file_path": PATH}`` types PATH into the Files tab's path field; ``{"view_size": N}`` picks the
        sphere's resolution (the combo's values); ``{"key": "F12"}`` presses and releases a key (ImGui's
        name), then waits for a screenshot it asked for; ``{"quit": true}``.
        """
        script = self.script
        if script.index >= len(script.actions):
            self._quit = True
            return
        action = script.actions[script.index]
        step = script.frame_in_action
        script.frame_in_action += 1
        done = False
        if "wait" in action:
            done = step >= int(action["wait"])
        elif "wait_complete" in action:
            done = step > 1 and self._idle()
            if step > int(action.get("timeout", 2000)):
                script.log.append("wait_complete: timed out")
                done = True
        elif "mark" in action:
            script.mark = action["mark"]
            done = True
        elif "set" in action:
            self.values = self.material.resolve({**self.values, **action["set"]})
            done = True
        elif "drag" in action:
            frames = int(action.get("frames", 10))
            if step == 0:
                point = self._target_point(action["drag"], float(action.get("from", 0.5)))
                if point is None:
                    if step > 60:
                        script.log.append(f"drag: no item {action['drag']!r}")
                        done = True
                    script.frame_in_action = 0 if point is None else script.frame_in_action
                    script.waited += 1
                    if script.waited > 60:
                        script.log.append(f"drag: no item {action['drag']!r}")
                        script.waited = 0
                        done = True
                else:
                    self._mouse(io, point)
            elif step == 1:
                io.add_mouse_button_event(0, True)
            elif step <= frames + 1:
                t = (step - 1) / frames
                f0, f1 = float(action.get("from", 0.5)), float(action.get("to", 0.5))
                point = self._target_point(action["drag"], f0 + t * (f1 - f0))
                if point is not None:
                    # Back and forth (repeat > 1) keeps a long drag within the slider.
                    self._mouse(io, point)
            else:
                io.add_mouse_button_event(0, False)
                script.log.append(f"dragged {action['drag']}")
                done = True
        elif "click" in action:
            if step == 0:
                point = self._target_point(action["click"])
                if point is None:
                    script.frame_in_action = 0
                    script.waited += 1
                    if script.waited > 60:
                        script.log.append(f"click: no item {action['click']!r}")
                        script.waited = 0
                        done = True
                else:
                    script.waited = 0
                    self._mouse(io, point)
            elif step == 1:
                io.add_mouse_button_event(0, True)
            elif step == 2:
                io.add_mouse_button_event(0, False)
            else:
                script.log.append(f"clicked {action['click']}")
                done = True
        elif "screenshot" in action:
            if step == 0:
                self._pending_screenshot = str(action["screenshot"])
            done = self._pending_screenshot is None
            if step > int(action.get("timeout", 3000)):
                script.log.append("screenshot: timed out")
                done = True
        elif "key" in action:
            from imgui_bundle import imgui

            if step <= 1:
                io.add_key_event(getattr(imgui.Key, str(action["key"]).lower()), step == 0)
            else:
                done = self._pending_screenshot is None
                if step > int(action.get("timeout", 3000)):
                    script.log.append(f"key {action['key']}: timed out")
                    done = True
                if done:
                    script.log.append(f"pressed {action['key']}")
        elif "window_screenshot" in action:
            if step == 0:
                self._pending_window_shot = str(action["window_screenshot"])
            done = step > 0 and self._pending_window_shot is None
        elif "file_path" in action:
            self.file_path = str(action["file_path"])
            done = True
        elif "view_size" in action:
            self.view_size = int(action["view_size"])
            done = True
        elif "focus" in action:  # bring a docked window's tab to the front, as a click on its tab does
            self._focused_request = str(action["focus"])
            done = True
        elif "write" in action:  # what a user's editor does to the material file between two reloads
            Path(action["write"]).write_text(str(action["text"]))
            script.log.append(f"wrote {action['write']}")
            done = True
        elif "quit" in action:
            self._quit = True
            done = True
        else:
            script.log.append(f"unknown action {action!r}")
            done = True
        if done:
            script.index += 1
            script.frame_in_action = 0

    def _mouse(self, io, point) -> None:
        self.script.mouse = point
        io.add_mouse_pos_event(float(point[0]), float(point[1]))

    def _idle(self) -> bool:
        """Nothing left to draw: the sphere, and the compare pair when it is on and shown."""
        jobs = [self.jobs["main"]]
        if self.compare["on"] and "Compare" in getattr(self, "_visible", ()):
            jobs += [self.jobs["compare_a"], self.jobs["compare_b"]]
        return all(job.complete or job.error is not None for job in jobs) and not self._dragging

    def _record(self, label: str) -> None:
        """Remember the last item's screen rectangle under ``label`` (for scripted input)."""
        from imgui_bundle import imgui

        lo, hi = imgui.get_item_rect_min(), imgui.get_item_rect_max()
        self.rects[label] = (lo.x, lo.y, hi.x, hi.y)

    # -- UI ----------------------------------------------------------------------------------------

    @property
    def _dragging(self) -> bool:
        from imgui_bundle import imgui

        return bool(imgui.is_any_item_active() and imgui.is_mouse_down(0)) or self._orbit_drag

    def _layout(self, dockspace) -> None:
        from imgui_bundle import imgui

        internal = imgui.internal
        internal.dock_builder_remove_node(dockspace)
        internal.dock_builder_add_node(dockspace, internal.DockNodeFlagsPrivate_.dock_space)
        internal.dock_builder_set_node_size(dockspace, imgui.get_main_viewport().size)
        split = internal.dock_builder_split_node(dockspace, imgui.Dir.left, 0.26)
        left, rest = split.id_at_dir, split.id_at_opposite_dir
        split = internal.dock_builder_split_node(rest, imgui.Dir.right, 0.40)
        right, centre = split.id_at_dir, split.id_at_opposite_dir
        split = internal.dock_builder_split_node(right, imgui.Dir.down, 0.45)
        right_bottom, right_top = split.id_at_dir, split.id_at_opposite_dir
        internal.dock_builder_dock_window("Parameters", left)
        internal.dock_builder_dock_window("Files", left)
        internal.dock_builder_dock_window("Sphere", centre)
        internal.dock_builder_dock_window("Compare", centre)
        internal.dock_builder_dock_window("Slice", centre)
        internal.dock_builder_dock_window("Scatter", centre)
        internal.dock_builder_dock_window("Spectrum", right_top)
        internal.dock_builder_dock_window("Polar", right_top)
        internal.dock_builder_dock_window("Strips", right_bottom)
        internal.dock_builder_finish(dockspace)

    def _ui(self) -> None:
        from imgui_bundle import imgui

        dockspace = imgui.dock_space_over_viewport()
        if not self._layout_done:
            self._layout(dockspace)
            self._layout_done = True
        self._visible: set[str] = set()
        self._menu()
        self._keys()
        for name, draw in (("Parameters", self._ui_parameters), ("Files", self._ui_files), ("Sphere", self._ui_sphere),
                           ("Compare", self._ui_compare), ("Slice", self._ui_slice), ("Scatter", self._ui_scatter),
                           ("Spectrum", self._ui_spectrum), ("Polar", self._ui_polar), ("Strips", self._ui_strips)):
            expanded, _ = imgui.begin(name)
            if expanded:
                self._visible.add(name)
                draw()
            imgui.end()
        if name := self._focused_request:
            imgui.set_window_focus(name)
            self._focused_request = None

    _focused_request: str | None = None

    def _keys(self) -> None:
        from imgui_bundle import imgui

        io = imgui.get_io()
        if io.want_text_input:
            return
        if imgui.is_key_pressed(imgui.Key.f5):
            self.reload()
        if imgui.is_key_pressed(imgui.Key.f12):
            self._pending_screenshot = self._screenshot_name()

    def _menu(self) -> None:
        from imgui_bundle import imgui

        if not imgui.begin_main_menu_bar():
            return
        if imgui.begin_menu("File"):
            if imgui.menu_item_simple("Reload material", "F5"):
                self.reload()
            if imgui.menu_item_simple("Screenshot of the active view", "F12"):
                self._pending_screenshot = self._screenshot_name()
            if imgui.menu_item_simple("Quit"):
                self._quit = True
            imgui.end_menu()
        presets = self.presets()
        if imgui.begin_menu("Presets", bool(presets)):
            for name, preset in presets.items():
                if imgui.menu_item_simple(name, "", self.preset == name):
                    self.apply_preset(name)
                self._record(f"menu_preset:{name}")
                if imgui.is_item_hovered():
                    imgui.set_tooltip(f"{preset.figure}: {preset.description}")
            imgui.end_menu()
        self._record("menu_presets")
        imgui.text(f"   {self._frame_label()}")
        imgui.end_main_menu_bar()

    def _frame_label(self) -> str:
        recent = [f["ms"] for f in self.frame_times[-30:]]
        if not recent:
            return ""
        ms = float(np.median(recent))
        return f"frame {ms:.1f} ms ({1e3 / max(ms, 1e-3):.0f} fps)"

    def _ui_parameters(self) -> None:
        from imgui_bundle import imgui

        imgui.text_wrapped(str(self.material_path))
        reload_clicked = imgui.button("Reload (F5)")
        self._record("reload")
        if reload_clicked:
            self.reload()
        if self.error:
            imgui.push_text_wrap_pos(0.0)
            imgui.text_colored(imgui.ImVec4(1.0, 0.35, 0.3, 1.0), self.error)
            imgui.pop_text_wrap_pos()
        presets = self.presets()
        if presets:
            names = list(presets)
            if imgui.begin_combo("Preset", self.preset or "(none)"):
                for name in names:
                    clicked, _ = imgui.selectable(name, self.preset == name)
                    self._record(f"preset:{name}")
                    if clicked:
                        self.apply_preset(name)
                imgui.end_combo()
            self._record("preset_combo")
        imgui.separator()
        io = imgui.get_io()
        for parameter in self.material.parameters:
            self._parameter_widget(imgui, io, parameter)
        imgui.separator()
        imgui.text("Light and camera")
        changed, theta = imgui.slider_float("light theta", self.light[0], 0.0, 180.0, "%.1f deg")
        if changed:
            self.light[0] = theta
        changed, phi = imgui.slider_float("light phi", self.light[1], -180.0, 180.0, "%.1f deg")
        if changed:
            self.light[1] = phi
        changed, yaw = imgui.slider_float("camera yaw", self.camera[0], -180.0, 180.0, "%.1f deg")
        if changed:
            self.camera[0] = yaw
        changed, pitch = imgui.slider_float("camera pitch", self.camera[1], -89.0, 89.0, "%.1f deg")
        if changed:
            self.camera[1] = pitch
        changed, zoom = imgui.slider_float("zoom", self.zoom, 1.0, 8.0, "%.2fx")
        if changed:
            self.zoom = zoom
        if imgui.button("Reset camera"):
            self.camera, self.zoom = [0.0, 0.0], 1.0
        imgui.separator()
        changed, exposure = imgui.slider_float("exposure", self.exposure, 0.05, 20.0, "%.2f", imgui.SliderFlags_.logarithmic)
        self._record("exposure")
        if changed:
            self.exposure = exposure
        _, self.gamut = imgui.checkbox("gamut overlay (outside sRGB)", self.gamut)
        sizes = [str(s) for s in VIEW_SIZES]
        changed, index = imgui.combo("resolution", VIEW_SIZES.index(self.view_size) if self.view_size in VIEW_SIZES else 2, sizes)
        if changed:
            self.view_size = VIEW_SIZES[index]
        imgui.text(self._frame_label())
        if self.status:
            imgui.text_wrapped(self.status)

    def _parameter_widget(self, imgui, io, parameter) -> None:
        """A parameter's widget: slider (integer or float), checkbox or colour editor, plus a typed field."""
        name, kind = parameter.name, widget_kind(parameter)
        value = self.values[name]
        new = value
        imgui.push_id(name)
        no_ctrl_input = imgui.SliderFlags_.no_input  # Ctrl-click resets instead of typing; the field types
        if kind == "int":
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
            if changed:
                new = tuple(float(c) for c in v)
        self._record(f"param:{name}")
        if imgui.is_item_clicked() and io.key_ctrl:
            new = parameter.default
        if imgui.is_item_hovered():
            bounds = "" if parameter.min is None else f" in [{parameter.min:g}, {parameter.max:g}]"
            imgui.set_tooltip(f"{name}: {parameter.type}{bounds}, default {parameter.default}; Ctrl-click resets")
        if kind in ("int", "float"):
            imgui.same_line()
            imgui.set_next_item_width(-1)
            typed, text = imgui.input_text("##typed", f"{float(new):g}", imgui.InputTextFlags_.enter_returns_true | imgui.InputTextFlags_.chars_scientific)
            self._record(f"typed:{name}")
            if typed:
                try:
                    new = parameter.coerce(text)
                    self.status = ""
                except ValueError as error:
                    self.status = f"{name}: {error}"
        imgui.pop_id()
        if new != value:
            self.values = {**self.values, name: new}
            self.preset = None

    def _ui_files(self) -> None:
        from imgui_bundle import imgui

        imgui.text_wrapped("Parameter sets: .json, or BRDF Explorer's .bparam. Materials: .brd / .brdf.")
        _, self.file_path = imgui.input_text("path", self.file_path)
        if imgui.button("Save parameters"):
            try:
                save_values(self.file_path, self.material, self.values)
                self.status = f"saved {self.file_path}"
            except LocatedError as error:
                self.status = str(error)
        imgui.same_line()
        if imgui.button("Load parameters"):
            try:
                loaded = load_values(self.file_path, self.material)
                self.values = self.material.resolve({**self.values, **loaded.values})
                self.status = f"loaded {self.file_path}" + (f"; skipped {', '.join(loaded.skipped)}" if loaded.skipped else "")
            except LocatedError as error:
                self.status = str(error)
        if imgui.button("Open material"):
            self.reload(Path(self.file_path))
        self._record("open_material")
        imgui.same_line()
        if imgui.button("Screenshot (F12)"):
            self._pending_screenshot = self._screenshot_name()
        if self.status:
            imgui.text_wrapped(self.status)

    # -- the sphere ------------------------------------------------------------------------------

    def _light_vector(self) -> tuple[float, float, float]:
        """The light in view space: the world light turned by the inverse of the orbit camera (pyrr)."""
        from pyrr import Matrix33

        from .views.geometry import light_direction

        direction = light_direction(tuple(self.light)).astype(np.float64)
        yaw, pitch = np.radians(self.camera)
        rotation = Matrix33.from_x_rotation(pitch) @ Matrix33.from_y_rotation(yaw)
        if yaw == 0.0 and pitch == 0.0:
            return tuple(float(c) for c in light_direction(tuple(self.light)))  # bit for bit the headless light
        turned = np.asarray(rotation) @ direction
        return tuple(float(c) for c in (turned / np.linalg.norm(turned)).astype(np.float32))

    def _main_view(self) -> str:
        if self.mode == "sphere" and self._has_reflectance(self.material):
            return "sphere"
        return "lit"

    def _ui_sphere(self) -> None:
        from imgui_bundle import imgui

        for mode in MODES:
            if mode == "env" and self.env is None:
                continue
            if imgui.radio_button(mode, self.mode == mode):
                self.mode = mode
            self._record(f"mode:{mode}")
            imgui.same_line()
        imgui.new_line()
        if self.mode == "sphere" and not self._has_reflectance(self.material):
            imgui.text_colored(imgui.ImVec4(1, 0.7, 0.3, 1), "this material has no reflectance(cos_theta): showing lit")
        size = (self.view_size, self.view_size)
        job = self.jobs["main"]
        if self.mode == "env" and self.env is not None:
            self._request_env(size)
            texture = self._env_texture
        else:
            values = self._prepared_values(self.values)
            job.request(self.material, values, self._main_view(), size, light=self._light_vector(), dragging=self._dragging)
            texture = self.display.target("main", size)
            self._display_requests = getattr(self, "_display_requests", {})
            self._display_requests["main"] = (job, None)
        self._image(texture, size, "sphere_image", interactive=True)
        state = "done" if job.complete else ("preview %dx%d" % job.preview_size if job.has_preview and job.refined_rows == 0 else f"refining {100 * job.progress:.0f}%")
        imgui.text(f"{self._main_view()} {size[0]}x{size[1]}: {state}; {self._frame_label()}")
        if job.error:
            imgui.text_colored(imgui.ImVec4(1.0, 0.35, 0.3, 1.0), job.error)

    def _prepared_values(self, values: dict) -> dict:
        """
        The parameter values the sphere shows. While a slider is dragged the host's tables (the tabulated
        method's ~10 ms, a stack's layers) are built on a worker thread as the frame draws, and the sphere
        shows the newest values whose tables are ready: one frame behind the slider. Otherwise they are
        built here, so a released slider always shows its own values.
        """
        import concurrent.futures

        if self.renderer.model_ready(self.material, values):
            self._ready_values = dict(values)
            return values
        if self._dragging and self._ready_values is not None:
            if self._prefetch is not None and self._prefetch.done():
                if self._prefetch.exception() is None:
                    self._ready_values = self._prefetch_values  # the newest values whose tables are built
                self._prefetch = None
            if self._prefetch is None:
                if self._executor is None:
                    self._executor = concurrent.futures.ThreadPoolExecutor(max_workers=1, thread_name_prefix="tables")
                self._prefetch_values = dict(values)
                self._prefetch = self._executor.submit(self.renderer.prepare_model, self.material, self._prefetch_values)
            return self._ready_values
        if self._prefetch is not None:
            concurrent.futures.wait([self._prefetch])  # its errors resurface in bind, with the current values
        self._ready_values = dict(values)
        return values

    _ready_values: dict | None = None
    _prefetch_values: dict | None = None
    _prefetch = None
    _executor = None

    def _image(self, texture, size, label: str, interactive: bool = False) -> None:
        """An image fitted to the window, flipped to rows-from-the-top, zoomed about its centre."""
        from imgui_bundle import imgui

        avail = imgui.get_content_region_avail()
        scale = min(1.0, max(avail.x, 16) / size[0], max(avail.y - 24, 16) / size[1]) if size[0] > 0 else 1.0
        shown = imgui.ImVec2(size[0] * scale, size[1] * scale)
        half = 0.5 / (self.zoom if interactive else 1.0)
        imgui.image(imgui.ImTextureRef(texture.glo), shown, imgui.ImVec2(0.5 - half, 0.5 + half), imgui.ImVec2(0.5 + half, 0.5 - half))
        self._record(label)
        if interactive:
            self._sphere_mouse(imgui)

    def _sphere_mouse(self, imgui) -> None:
        """Left-drag orbits the camera, right-drag puts the light where the mouse is, the wheel zooms."""
        io = imgui.get_io()
        hovered = imgui.is_item_hovered()
        if hovered and imgui.is_mouse_clicked(0):
            self._orbit_drag = True
        if not imgui.is_mouse_down(0):
            self._orbit_drag = False
        if self._orbit_drag:
            delta = io.mouse_delta
            self.camera[0] = float((self.camera[0] + 0.4 * delta.x + 180.0) % 360.0 - 180.0)
            self.camera[1] = float(np.clip(self.camera[1] + 0.4 * delta.y, -89.0, 89.0))
        if hovered and imgui.is_mouse_down(1):
            x0, y0, x1, y1 = self.rects["sphere_image"]
            x = (2.0 * (io.mouse_pos.x - x0) / max(x1 - x0, 1) - 1.0) / self.zoom
            y = (1.0 - 2.0 * (io.mouse_pos.y - y0) / max(y1 - y0, 1)) / self.zoom
            r = min(np.hypot(x, y), 1.0)
            self.light = [float(np.degrees(np.arcsin(r))), float(np.degrees(np.arctan2(y, x)))]
        if hovered and io.mouse_wheel:
            self.zoom = float(np.clip(self.zoom * (1.1 ** io.mouse_wheel), 1.0, 8.0))

    # -- env (explorer/env.py) ------------------------------------------------------------

    def _make_env(self) -> None:
        from . import env

        self.env = env

    def _request_env(self, size) -> None:
        """The env mode: progressive Monte Carlo under an environment map (explorer.env), restarted on change."""
        env = self.env
        key = (id(self.material), tuple(sorted(self.values.items())), size, tuple(self.camera), tuple(self.light))
        if getattr(self, "_env_key", None) != key or getattr(self, "_env_render", None) is None:
            render = getattr(self, "_env_render", None)
            # Another material (Files > Open, Reload) needs a render of its own: resetting the old one with
            # the new values would bind them to the old material's uniforms.
            if render is None or getattr(self, "_env_size", None) != size or render.material is not self.material:
                if render is not None:
                    render.release()
                self._env_map = getattr(self, "_env_map", None) or env.EnvironmentMap.default()
                self._env_render = env.ProgressiveEnvRender(self.renderer, self.material, self.values, self._env_map, *size)
                self._env_size = size
            else:
                self._env_render.reset(values=self.values)
            self._env_key = key
        self._env_pending = True
        from .app_views import AccumulatedImage

        if getattr(self, "_env_source", None) is None or self._env_source.render is not self._env_render:
            self._env_source = AccumulatedImage(self._env_render)
        self._display_requests = getattr(self, "_display_requests", {})
        self._display_requests["main"] = (self._env_source, None)
        self._env_texture = self.display.target("main", size)

    # -- compare ---------------------------------------------------------------------------------------

    def _ui_compare(self) -> None:
        from imgui_bundle import imgui

        c = self.compare
        _, c["on"] = imgui.checkbox("compare", c["on"])
        self._record("compare_on")
        names = app_data.method_names(self.material)
        if imgui.radio_button("two methods", c["kind"] == "methods") and names:
            c["kind"] = "methods"
        imgui.same_line()
        if imgui.radio_button("two parameter sets (A = current | B)", c["kind"] == "sets"):
            c["kind"] = "sets"
        if c["kind"] == "methods" and names:
            labels = [f"{m}: {n}" for m, n in names.items()]
            keys = list(names)
            _, ia = imgui.combo("A (left)", keys.index(c["a"]) if c["a"] in keys else 0, labels)
            _, ib = imgui.combo("B (right)", keys.index(c["b"]) if c["b"] in keys else 0, labels)
            c["a"], c["b"] = keys[ia], keys[ib]
        else:
            if imgui.button("B := current parameters"):
                c["values_b"] = dict(self.values)
        _, c["heat"] = imgui.checkbox("dE2000 heat-map (viridis, 0 to 10)", c["heat"])
        if not c["on"]:
            imgui.text("(off)")
            return
        size = (self.view_size // 2, self.view_size // 2) if self.view_size > 256 else (self.view_size, self.view_size)
        if c["kind"] == "methods" and names:
            values_a = {**self.values, "method": float(c["a"])}
            values_b = {**self.values, "method": float(c["b"])}
        else:
            values_a, values_b = self.values, self.material.resolve({k: v for k, v in c["values_b"].items() if any(p.name == k for p in self.material.parameters)})
        light = self._light_vector()
        dragging = self._dragging
        self.jobs["compare_a"].request(self.material, values_a, self._main_view(), size, light=light, dragging=dragging)
        self.jobs["compare_b"].request(self.material, values_b, self._main_view(), size, light=light, dragging=dragging)
        if c["heat"] and self._heat_texture is not None:
            self._image(self._heat_texture, size, "compare_image")
        else:
            self._display_requests = getattr(self, "_display_requests", {})
            self._display_requests["compare"] = (self.jobs["compare_a"], self.jobs["compare_b"])
            self._image(self.display.target("compare", size), size, "compare_image")
        if self.mean_delta_e is not None:
            imgui.text(f"mean dE2000 over the sphere: {self.mean_delta_e:.3f}")
        else:
            imgui.text("mean dE2000: (rendering)")

    def _update_heat(self) -> None:
        a, b = self.jobs["compare_a"], self.jobs["compare_b"]
        if not (self.compare["on"] and a.complete and b.complete):
            return
        generation = (a.generation, b.generation)
        if generation == self._heat_generation:
            return
        image_a, image_b = a.read(), b.read()
        mask = app_data.disc_mask(*a.size)
        delta_e, self.mean_delta_e = app_data.delta_e_map(image_a, image_b, mask)
        rgba = app_data.heat_map_rgba(delta_e)
        rgba[~mask] = (0, 0, 0, 255)
        if self._heat_texture is None or self._heat_texture.size != a.size:
            self._heat_texture = self.ctx.texture(a.size, 4)
        self._heat_texture.write(np.ascontiguousarray(rgba[::-1]).tobytes())
        self._heat_generation = generation

    # -- the other views -----------------------------------------------------------------------------

    def _ui_brdf_view(self, name: str, view: str) -> None:
        from imgui_bundle import imgui

        size = (SIDE_VIEW_SIZE, SIDE_VIEW_SIZE)
        job = self.jobs[name]
        job.request(self.material, self.values, view, size, light=self._light_vector(), dragging=self._dragging)
        self._display_requests = getattr(self, "_display_requests", {})
        self._display_requests[name] = (job, None)
        self._image(self.display.target(name, size), size, f"{name}_image")
        imgui.text(("done" if job.complete else f"refining {100 * job.progress:.0f}%") + (f"  {job.error}" if job.error else ""))

    def _ui_slice(self) -> None:
        from imgui_bundle import imgui

        imgui.text("theta_h across (0-90 deg), theta_d down (0-90 deg), phi_d = 90 deg")
        self._ui_brdf_view("slice", "slice")

    def _ui_scatter(self) -> None:
        from imgui_bundle import imgui

        imgui.text("outgoing directions, radius ~ theta_o; BRDF*cos theta_o for the light")
        self._ui_brdf_view("scatter", "scatter")

    def _ui_strips(self) -> None:
        from imgui_bundle import imgui

        names = app_data.method_names(self.material)
        if not self._has_reflectance(self.material):
            imgui.text("this material has no reflectance(cos_theta)")
            return
        methods = [m for m in app_data.BRAGG_STRIP_METHODS if m in names] if self.material.model in app_data.BRAGG_MODELS else list(names) or [None]
        imgui.text("theta from 0 deg (left) to 90 deg (right)")
        width = STRIP_WIDTH
        for method in methods:
            job = self.strip_jobs.get(method)
            if job is None:
                from .app_views import ProgressiveView

                job = self.strip_jobs[method] = ProgressiveView(self.renderer, self.costs)
            values = self.values if method is None else {**self.values, "method": float(method)}
            job.request(self.material, values, "gradient", (width, 1), dragging=self._dragging)
            self._display_requests = getattr(self, "_display_requests", {})
            self._display_requests[f"strip{method}"] = (job, None)
            texture = self.display.target(f"strip{method}", (width, 1))
            avail = imgui.get_content_region_avail().x
            label = "" if method is None else f"{method} {names.get(method, '')}"
            imgui.image(imgui.ImTextureRef(texture.glo), imgui.ImVec2(max(avail - 110, 32), 22), imgui.ImVec2(0, 1), imgui.ImVec2(1, 0))
            imgui.same_line()
            imgui.text(label)

    def _ui_spectrum(self) -> None:
        from imgui_bundle import implot, imgui

        if self.material.model not in app_data.BRAGG_MODELS:
            imgui.text("the spectrum needs a Bragg mirror material (n1, n2, Lambda, delta, N)")
            return
        _, self.spectrum_theta = imgui.slider_float("theta", self.spectrum_theta, 0.0, 89.0, "%.1f deg")
        self._record("spectrum_theta")
        for key in self.spectrum_show:
            _, self.spectrum_show[key] = imgui.checkbox(key, self.spectrum_show[key])
            imgui.same_line()
        imgui.new_line()
        method = round_integer(self.values.get("method", 0))
        s = round_integer(self.values.get("s", 3))
        key = (tuple(sorted(self.values.items())), self.spectrum_theta)
        # While a slider is dragged the curves follow at most every DRAG_SPECTRUM_S (their ~3 ms of numpy
        # would otherwise come out of every frame of the sphere's); on release they catch up at once.
        throttled = self._dragging and time.perf_counter() - self._spectrum_time < DRAG_SPECTRUM_S
        if key != self._spectrum_key and not (throttled and self._spectrum is not None):
            self._spectrum_time = time.perf_counter()
            structure = not self._dragging
            self._spectrum = app_data.spectrum(self.values, self.spectrum_theta, method, s, structure=structure)
            if not structure and self._spectrum_structure is not None:
                old = self._spectrum_structure
                self._spectrum.gaps, self._spectrum.landmarks, self._spectrum.boxes = old.gaps, old.landmarks, old.boxes
            self._spectrum_key = key if structure else None
            if structure:
                self._spectrum_structure = self._spectrum
        sp = self._spectrum
        if implot.begin_plot("R(lambda)", imgui.ImVec2(-1, -1)):
            implot.setup_axes("wavelength (nm)", "reflectance")
            implot.setup_axes_limits(360, 830, 0, 1.05)
            show = self.spectrum_show
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
                implot.plot_line("average", sp.wavelengths, average, implot.Spec(line_weight=2.0))
            if show["envelope"]:
                implot.plot_line("envelope", sp.wavelengths, 0.5 * (sp.envelope["s"] + sp.envelope["p"]))
            if show["boxes"]:
                for polarisation, boxes in sp.boxes.items():
                    xs, ys = app_data.boxes_polyline(boxes)
                    if xs.size:
                        implot.plot_line(f"boxes {polarisation}", xs, ys)
            implot.end_plot()

    _spectrum_structure = None

    def _ui_polar(self) -> None:
        from imgui_bundle import implot, imgui

        job = self.jobs["polar"]
        job.request(self.material, self.values, "scatter", (POLAR_SAMPLES, 1), light=self._light_vector(), dragging=False)
        if job.complete and job.generation != self._polar_generation:
            self._polar = app_data.polar_curve(job.read())
            self._polar_generation = job.generation
        imgui.text(f"plane of incidence (light theta = {self.light[0]:.1f} deg); radius = BRDF (1/sr)")
        if self._polar is None:
            return
        theta, brdf = self._polar
        if implot.begin_plot("polar", imgui.ImVec2(-1, -1), implot.Flags_.equal):
            implot.setup_axes("", "")
            radians = np.radians(theta)
            for channel, colour in enumerate(((1, 0.3, 0.3, 1), (0.3, 1, 0.3, 1), (0.4, 0.5, 1, 1))):
                r = np.clip(brdf[:, channel], 0.0, None)
                implot.plot_line("RGB"[channel], r * np.sin(radians), r * np.cos(radians), implot.Spec(line_color=imgui.ImVec4(*colour)))
            implot.end_plot()

    # -- GL work of a frame ------------------------------------------------------------------------------

    def _gl_work(self) -> float:
        """Advance the visible views within the frame's budget (the sphere first), then the display passes."""
        from .app_views import FRAME_BUDGET_MS

        start = time.perf_counter()
        budget = FRAME_BUDGET_MS
        order = []
        if "Sphere" in self._visible and self.mode != "env":
            order.append(self.jobs["main"])
        if "Compare" in self._visible and self.compare["on"]:
            order += [self.jobs["compare_a"], self.jobs["compare_b"]]
        if "Strips" in self._visible:
            order += list(self.strip_jobs.values())
        if "Slice" in self._visible:
            order.append(self.jobs["slice"])
        if "Scatter" in self._visible:
            order.append(self.jobs["scatter"])
        if "Polar" in self._visible:
            order.append(self.jobs["polar"])
        if self._pending_screenshot and self.mode != "env":
            order.insert(0, self.jobs["main"])
        dragging = self._dragging
        for index, job in enumerate(order):
            remaining = budget - (time.perf_counter() - start) * 1e3
            if dragging:
                # While a slider moves the sphere comes first and gets a preview that fits with the UI's
                # own ~30 ms in a 15 fps frame; the other views get what little is left.
                remaining = min(remaining, DRAG_BUDGET_MS) if index == 0 else min(remaining, SIDE_DRAG_BUDGET_MS)
            if remaining <= 0:
                break
            job.work(remaining)
        if getattr(self, "_env_pending", False) and self.mode == "env":
            self._env_work(budget - (time.perf_counter() - start) * 1e3)
        self._env_pending = False
        if "Compare" in self._visible:
            self._update_heat()
        for key, (a, b) in getattr(self, "_display_requests", {}).items():
            if a.full is not None:
                self.display.draw(key, a, b, split=0.5 if b is not None else 2.0, exposure=self.exposure, gamut=self.gamut)
        self._display_requests = {}
        return (time.perf_counter() - start) * 1e3

    def _env_work(self, budget_ms: float) -> None:
        # Bands of rows when one sample costs more than the budget; the display pass divides by the counts.
        self._env_render.advance(max(0.5 * budget_ms, 5.0))

    # -- screenshots -------------------------------------------------------------------------------------

    def _screenshot_name(self) -> str:
        SCREENSHOT_DIR.mkdir(exist_ok=True)
        stem = f"{Path(self.material_path).stem}_{self._main_view()}"
        index = 1
        while (SCREENSHOT_DIR / f"{stem}_{index}.png").exists():
            index += 1
        return str(SCREENSHOT_DIR / f"{stem}_{index}.png")

    _pending_window_shot: str | None = None

    def _window_shot(self) -> None:
        """The whole window as a PNG (the README's picture; the tests' check of what is on screen)."""
        from PIL import Image

        import OpenGL.GL as gl

        # PyOpenGL, not moderngl: moderngl reads "colour attachment 0", which the window's own
        # framebuffer does not have (GL_INVALID_OPERATION).
        width, height = self.ctx.screen.size
        gl.glBindFramebuffer(gl.GL_READ_FRAMEBUFFER, 0)
        gl.glReadBuffer(gl.GL_BACK)
        gl.glPixelStorei(gl.GL_PACK_ALIGNMENT, 1)
        data = gl.glReadPixels(0, 0, width, height, gl.GL_RGB, gl.GL_UNSIGNED_BYTE)
        pixels = np.frombuffer(data, dtype=np.uint8).reshape(height, width, 3)[::-1]
        Image.fromarray(np.ascontiguousarray(pixels), mode="RGB").save(self._pending_window_shot)
        self.screenshots.append(self._pending_window_shot)
        self._pending_window_shot = None

    def _take_screenshot(self) -> None:
        """Write the active view (PNG, 8-bit sRGB with the exposure; and its linear ``.npy``) once complete."""
        if self._pending_screenshot is None:
            return
        from .images import OutputError, write_image

        samples = None
        if self.mode == "env" and self.env is not None:
            render = getattr(self, "_env_render", None)
            if render is None or render.material is not self.material or render.samples == 0 or render._band_rows:
                return  # written at the first whole sample of the material shown (every pixel the same count)
            image = np.asarray(render.image(), dtype=np.float32)
            samples = render.samples
        else:
            job = self.jobs["main"]
            if job.error is not None:
                self.status = f"no screenshot: {job.error}"
                self._pending_screenshot = None
                return
            if not job.complete:
                return  # written when the image is refined (the window stays responsive meanwhile)
            image = job.read()
        path = Path(self._pending_screenshot)
        self._pending_screenshot = None
        try:
            write_image(image, path.with_suffix(".png"), exposure=self.exposure)
            write_image(image, path.with_suffix(".npy"))
        except OutputError as error:
            self.status = str(error)
            return
        self.screenshots.append(str(path.with_suffix(".png")))
        self.screenshot_info[str(path.with_suffix(".png"))] = {
            "material": str(self.material_path), "view": "env" if samples is not None else self._main_view(),
            "values": {k: list(v) if isinstance(v, tuple) else v for k, v in self.values.items()}, "samples": samples,
        }
        self.status = f"wrote {path.with_suffix('.png')} and {path.with_suffix('.npy')}"


def run_app(material_path, preset: str | None = None, *, script=None, report=None, window_size=DEFAULT_WINDOW,
            view_size: int = DEFAULT_VIEW_SIZE, is_default: bool = False) -> int:
    """Open the explorer on ``material_path``; :class:`AppError` when no window can be opened."""
    app = App(material_path, preset, script=script, report=report, window_size=window_size, view_size=view_size, is_default=is_default)
    return app.run()
