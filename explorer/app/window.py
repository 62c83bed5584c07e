"""
The explorer window: the material's lifecycle, the frame loop and the menu; the panels
(:mod:`explorer.app.panels`) draw the windows, the scheduler (:mod:`explorer.app.scheduler`) the
views, the robot (:mod:`explorer.app.script`) plays scripted sessions.
"""

from __future__ import annotations

import json
import os
import sys
import time
from pathlib import Path

from explorer.materials.brd import load_material
from explorer.errors import LocatedError
from explorer.app.panels import PANELS, dock_layout
from explorer.app.panels.base import record
from explorer.app.scheduler import Scheduler
from explorer.app.screenshots import screenshot_name, take_screenshot, window_shot
from explorer.app.script import ScriptRobot
from explorer.app.dialogs import OpenDialog
from explorer.app.state import DEFAULT_VIEW_SIZE, AppState, CompareState, MaterialEntry, has_reflectance, initial_values

DEFAULT_WINDOW = (1280, 800)
#: The frame whose windows the report calls the first screen (the layout is done and focused by then).
FIRST_SCREEN_FRAME = 3
#: The interpreter's thread switch interval while the app runs (Python's default: 5 ms). The table
#: prefetcher's worker thread holds the GIL between its numpy calls; each of the frame's many GL calls
#: through PyOpenGL (ImGui's backend) releases it and may wait a whole interval to get it back. At 0.5 ms a
#: dragged frame of the tabulated method took ~30% less time on a busy machine (docs/performance.md).
SWITCH_INTERVAL_S = 0.0005


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


class App:
    """
    The explorer window. ``run()`` returns when it is closed (or the script quits).

    Parameters
    ----------
    material_path : path of the ``.brd`` / ``.brdf`` file.
    preset : a preset of that material to start from.
    script, report : a scripted session (a list of actions, see :class:`explorer.app.script.ScriptRobot`)
        and where to write its JSON report.
    window_size : the window's size in pixels.
    view_size : the sphere's resolution; None: it follows the Sphere window's size.
    is_default : the default material (it opens on its tabulated method).
    more_paths : further materials to load beside the first (``open A B ...``); the first is shown.
    """

    def __init__(self, material_path, preset: str | None = None, *, script: list | None = None,
                 report: str | os.PathLike | None = None, window_size=DEFAULT_WINDOW, view_size: int | None = None,
                 is_default: bool = False, more_paths=(), maps: str | None = None):
        material = load_material(Path(material_path))
        values = initial_values(material, preset, is_default)
        if maps is not None:  # the folder's fixed values (checked by the command): the maps complete them
            from explorer.views.surface_texture import MapTexture

            values = material.resolve(MapTexture.from_folder(maps, material, values)[1])
        self.state = AppState(
            material_path=Path(material_path), material=material, values=values, compare=CompareState(values_b=dict(values)),
            preset=preset, view_size=int(view_size or DEFAULT_VIEW_SIZE), view_size_auto=view_size is None,
            mode="sphere" if has_reflectance(material) else "lit", maps_folder=str(maps or ""),
        )
        self.state.materials.append(MaterialEntry(Path(material_path), material, values, self.state.next_colour()))
        for path in more_paths:
            self._add_material(Path(path), initial_values(load_material(Path(path)), None, False))
        self.state.sync_selected()
        self.dialog = OpenDialog()
        self.robot = ScriptRobot(script) if script is not None else None
        self.report_path = Path(report) if report else None
        self.window_size = tuple(window_size)
        self.ctx = self.renderer = self.scheduler = None  # made with the window (run)
        self.panels: list = []
        self._presets: tuple[tuple, dict] | None = None  # (material key, its presets): read once per material
        self._layout_done = False
        self._last_values_key = None

    # -- material --------------------------------------------------------------------------------

    def presets(self) -> dict:
        """The presets of the open material (``{}`` when it has none)."""
        from explorer.materials.presets import PresetError, presets_for

        material = self.state.material
        key = (str(material.path), id(material))
        if self._presets is None or self._presets[0] != key:
            try:
                self._presets = (key, presets_for(material.path).presets)
            except PresetError:
                self._presets = (key, {})
        return self._presets[1]

    def apply_preset(self, name: str) -> None:
        state = self.state
        preset = self.presets()[name]
        state.values = state.material.resolve({**state.values, **preset.values})
        state.preset = name
        state.status = f"preset {name}: {preset.description}"

    def reload(self, path: Path | None = None) -> bool:
        """Read the material from disk again (or ``path``); on any error keep the last good one."""
        state = self.state
        path = Path(path) if path is not None else state.material_path
        try:
            material = load_material(path)
            known = {p.name for p in material.parameters}
            values = {}
            for name, value in state.values.items():
                if name in known:
                    try:
                        values[name] = material.parameter(name).coerce(value)
                    except ValueError:
                        pass
            values = material.resolve(values)
            view = "lit" if state.mode == "env" or (state.mode == "sphere" and not has_reflectance(material)) else state.mode
            self.renderer.program(material, view, values)  # compile now: a broken shader is reported here
        except LocatedError as error:
            state.error = str(error)
            return False
        state.material, state.material_path, state.values = material, path, values
        state.sync_selected()
        # Nothing of the previous material's values may reach the new one's uniforms: the compare view's
        # set B (its ranges may differ: thin_film's method 5 is no mirror method) and the values shown
        # while a slider drags. The env render follows the material (EnvSphere.request). The mode stays
        # as chosen: a material without reflectance() is shown lit in the sphere mode.
        state.compare.values_b = dict(values)
        self.scheduler.prefetcher.forget()
        state.error = ""
        state.status = f"loaded {path}"
        return True

    def _add_material(self, path: Path, values: dict) -> MaterialEntry:
        material = load_material(path)
        entry = MaterialEntry(path, material, material.resolve(values), self.state.next_colour())
        self.state.materials.append(entry)
        return entry

    def open_materials(self, paths) -> int:
        """
        Load ``paths`` beside the open materials (File > Open...) and show the last one loaded; a file that
        fails is reported in the status line (its one-line error) and skipped. Returns how many loaded.
        """
        state, errors, loaded = self.state, [], 0
        for path in paths:
            try:
                entry = self._add_material(Path(path), {})
                if self.renderer is not None:  # compile now: a broken shader is reported here, not drawn
                    self.renderer.program(entry.material, "lit", entry.values)
            except LocatedError as error:
                if state.materials and state.materials[-1].path == Path(path):
                    state.materials.pop()
                errors.append(str(error))
                continue
            loaded += 1
        if loaded:
            self.select(len(state.materials) - 1)
        state.error = errors[0] if errors else state.error
        state.status = f"opened {loaded} material{'s' * (loaded != 1)}" + (f"; {len(errors)} failed" if errors else "")
        return loaded

    def select(self, index: int) -> None:
        """Show the loaded material ``index`` in the sphere views and the Parameters window."""
        state = self.state
        if index == state.selected:
            return
        state.select(index)
        if self.scheduler is not None:
            self.scheduler.prefetcher.forget()
        state.status = f"showing {state.material_path.name}"

    def solo(self, index: int) -> None:
        """Only ``materials[index]`` visible in the plots (and shown)."""
        for i, entry in enumerate(self.state.materials):
            entry.visible = i == index
        self.select(index)

    def close(self, index: int) -> None:
        """Unload ``materials[index]`` (the last one stays)."""
        state = self.state
        if len(state.materials) <= 1:
            return
        state.sync_selected()
        closed = state.materials.pop(index)
        if state.compare.material_b > index:  # the same material stays B
            state.compare.material_b -= 1
        elif state.compare.material_b == index:
            state.compare.material_b = 0
        if index < state.selected:  # the shown material stays shown, one place up
            state.selected -= 1
        elif index == state.selected:
            state.show_entry(min(index, len(state.materials) - 1))
        if self.scheduler is not None:
            self.scheduler.prefetcher.forget()
        state.status = f"closed {closed.name}"

    # -- window and loop ---------------------------------------------------------------------------

    def _open_window(self):
        import glfw

        if not glfw.init():
            raise AppError("no display: glfw cannot initialise (is DISPLAY set?)")
        glfw.window_hint(glfw.CONTEXT_VERSION_MAJOR, 3)
        glfw.window_hint(glfw.CONTEXT_VERSION_MINOR, 3)
        glfw.window_hint(glfw.OPENGL_PROFILE, glfw.OPENGL_CORE_PROFILE)
        glfw.window_hint(glfw.OPENGL_FORWARD_COMPAT, True)
        title = f"bragg-explorer — {self.state.material_path.name}"
        window = glfw.create_window(self.window_size[0], self.window_size[1], title, None, None)
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

        from explorer.gpu import Renderer

        window = self._open_window()
        switch_interval = sys.getswitchinterval()
        sys.setswitchinterval(SWITCH_INTERVAL_S)
        try:
            self.ctx = moderngl.create_context(require=330)
            self.renderer = Renderer(self.ctx)
            imgui.create_context()
            implot.create_context()
            io = imgui.get_io()
            io.config_flags |= imgui.ConfigFlags_.docking_enable
            io.set_ini_filename(None)  # the layout is built here, the same every time
            _style(imgui, implot)
            _fonts(imgui)
            backend = GlfwRenderer(window)
            self.scheduler = Scheduler(self.renderer)
            self.panels = [panel(self) for panel in PANELS]
            last = time.perf_counter()
            while not glfw.window_should_close(window) and not self.state.quit:
                start = time.perf_counter()
                glfw.poll_events()
                if self.robot is not None:
                    self.robot.step(self, io)
                backend.process_inputs()
                imgui.new_frame()
                self._ui(imgui)
                ui_done = time.perf_counter()
                gl_ms = self.scheduler.work(self.state, [p for p in self.panels if p.title in self.state.visible], self.dragging)
                self.ctx.screen.use()
                self.ctx.clear(0.08, 0.08, 0.09)
                imgui.render()
                backend.render(imgui.get_draw_data())
                drawn = time.perf_counter()
                if self.state.pending_window_shot:
                    window_shot(self.state, self.ctx)
                glfw.swap_buffers(window)
                take_screenshot(self.state, self.scheduler)
                now = time.perf_counter()
                self._record_frame(now - last, now - start, gl_ms, ui_done - start, drawn - ui_done, now - drawn)
                last = now
            self.scheduler.prefetcher.shutdown()
            backend.shutdown()
            implot.destroy_context()
            imgui.destroy_context()
        finally:
            sys.setswitchinterval(switch_interval)
            glfw.destroy_window(window)
            glfw.terminate()
            self._write_report()
        return 0

    def _record_frame(self, frame_s, work_s, gl_ms, ui_s, draw_s, swap_s) -> None:
        """One frame's times (ms) and what the sphere showed, for the report."""
        mark = self.robot.mark if self.robot else None
        if mark is not None and mark not in self.state.plotted_log:  # what the plots drew when a script marked
            self.state.plotted_log[mark] = {k: list(v) for k, v in self.state.plotted.items()}
        if len(self.state.frame_times) == FIRST_SCREEN_FRAME:
            self.state.first_screen = sorted(self.state.visible)
        values_key = tuple(sorted((k, str(v)) for k, v in self.state.values.items()))
        changed, self._last_values_key = values_key != self._last_values_key, values_key
        self.state.frame_times.append({
            "changed": changed, "ms": frame_s * 1e3, "work_ms": work_s * 1e3, "gl_ms": gl_ms, "ui_ms": ui_s * 1e3,
            "imgui_draw_ms": draw_s * 1e3 - gl_ms, "swap_ms": swap_s * 1e3, "dragging": self.dragging,
            "mark": self.robot.mark if self.robot else None, "main": self.scheduler.main_report(),
            "env": self.scheduler.env.report(), "mode": self.state.mode,
            "table_ms": self.renderer.last_table_ms,
        })

    def _write_report(self) -> None:
        if self.report_path is None:
            return
        s = self.state
        report = {
            "material": str(s.material_path), "values": s.json_values(), "preset": s.preset, "mode": s.mode,
            "light": s.light, "camera": s.camera, "view_size": s.view_size, "exposure": s.exposure,
            "frames": s.frame_times, "screenshots": s.screenshots, "screenshot_info": s.screenshot_info,
            "error": s.error, "status": s.status, "script_log": self.robot.log if self.robot else [],
            "mean_delta_e": s.mean_delta_e, "inverse": s.inverse, "design": s.design, "accuracy": s.accuracy,
            "env": {"environment": s.environment, "rotation": s.env_rotation, "background": s.env_background,
                    "model": s.model, **s.env_progress},
            "view_size_auto": s.view_size_auto, "materials": [entry.report() for entry in s.materials], "selected": s.selected,
            "visible": sorted(s.visible), "slice": s.slice_report, "plotted": s.plotted, "plotted_log": s.plotted_log,
            "first_screen": s.first_screen, "items": sorted(s.rects), "dialog": self.dialog.log,
            "plots": s.plots, "texture_view": s.texture_view, "active_view": s.active_view, "strip_rows": s.strip_rows,
            "compare_size": s.compare.size, "rects": {name: list(rect) for name, rect in s.rects.items()},
            "polar": s.polar_report, "spectrum_legend": s.spectrum_legend,
        }
        from explorer.files import write_text_atomic

        write_text_atomic(self.report_path, json.dumps(report, indent=1))

    # -- UI ----------------------------------------------------------------------------------------

    @property
    def dragging(self) -> bool:
        """A slider (any active item under the left button) or the orbit camera is being dragged."""
        from imgui_bundle import imgui

        return bool(imgui.is_any_item_active() and imgui.is_mouse_down(0)) or self.state.orbit_drag

    def idle(self) -> bool:
        """Nothing left to draw: the sphere when shown, and the compare pair when it is on and shown (a hidden
        tab's view is not drawn: another material chosen behind it waits until its tab is in front)."""
        jobs = [self.scheduler.job("main")] if "Sphere" in self.state.visible or self.state.mode == "env" else []
        if self.state.compare.on and "Compare" in self.state.visible:
            jobs += [self.scheduler.job("compare_a"), self.scheduler.job("compare_b")]
        return all(job.complete or job.error is not None for job in jobs) and not self.dragging

    def _ui(self, imgui) -> None:
        state = self.state
        dockspace = imgui.dock_space_over_viewport()
        if not self._layout_done:
            dock_layout(imgui, dockspace, self.panels)
            self._layout_done = True
            # The first screen: the Spectrum window in front of its dock (Inverse and Design dock there too),
            # the Polar one for a material without a Bragg mirror's spectrum.
            from explorer.app.data import has_bragg_spectrum

            state.focus_request = state.focus_request or ("Spectrum" if has_bragg_spectrum(state.material) else "Polar")
        state.sync_selected()
        state.visible = set()
        self._menu(imgui)
        self._keys(imgui)
        self._dialogs(imgui)
        for panel in self.panels:
            expanded, _ = imgui.begin(panel.title)
            if expanded:
                state.visible.add(panel.title)
                pos, size = imgui.get_window_pos(), imgui.get_window_size()  # for scripted checks: nothing cut
                state.rects[f"window:{panel.title}"] = (pos.x, pos.y, pos.x + size.x, pos.y + size.y)
                if panel.title in ("Sphere", "Compare") and imgui.is_window_focused(imgui.FocusedFlags_.root_and_child_windows):
                    state.focused_view = panel.title
                panel.draw(imgui)
            imgui.end()
        # The active view (F12's): Compare when its tab is in front (and on), or focused beside a visible Sphere.
        compare_shown = "Compare" in state.visible and state.compare.on
        state.active_view = "compare" if compare_shown and ("Sphere" not in state.visible or state.focused_view == "Compare") else "sphere"
        if state.focus_request:
            imgui.set_window_focus(state.focus_request)
            state.focus_request = None

    def _keys(self, imgui) -> None:
        if imgui.get_io().want_text_input:
            return
        if imgui.is_key_pressed(imgui.Key.f5):
            self.reload()
        if imgui.is_key_pressed(imgui.Key.f12):
            self.state.pending_screenshot = screenshot_name(self.state)
        if imgui.is_key_pressed(imgui.Key.f1):
            self.state.show_controls = True
        if imgui.get_io().key_ctrl and imgui.is_key_pressed(imgui.Key.o):
            self.dialog.start(self.state)

    def _dialogs(self, imgui) -> None:
        """File > Open...'s answer when it comes, Help's windows."""
        from explorer.app.help import draw_help

        paths = self.dialog.poll(imgui, self.state)
        if paths:
            self.open_materials(paths)
        draw_help(imgui, self.state)

    def _menu(self, imgui) -> None:
        state = self.state
        if not imgui.begin_main_menu_bar():
            return
        if imgui.begin_menu("File"):
            if imgui.menu_item_simple("Open...", "Ctrl+O"):
                self.dialog.start(state)
            record(state, "menu_open")
            if imgui.menu_item_simple("Reload material", "F5"):
                self.reload()
            if imgui.menu_item_simple("Screenshot of the active view", "F12"):
                state.pending_screenshot = screenshot_name(state)
            if imgui.menu_item_simple("Quit"):
                state.quit = True
            imgui.end_menu()
        record(state, "menu_file")
        presets = self.presets()
        if imgui.begin_menu("Presets", bool(presets)):
            for name, preset in presets.items():
                if imgui.menu_item_simple(name, "", state.preset == name):
                    self.apply_preset(name)
                record(state, f"menu_preset:{name}")
                if imgui.is_item_hovered():
                    imgui.set_tooltip(f"{preset.figure}: {preset.description}")
            imgui.end_menu()
        record(state, "menu_presets")
        if imgui.begin_menu("Help"):
            if imgui.menu_item_simple("Keyboard and mouse", "F1"):
                state.show_controls = True
            record(state, "menu_controls")
            if imgui.menu_item_simple("About"):
                state.show_about = True
            record(state, "menu_about")
            imgui.end_menu()
        record(state, "menu_help")
        imgui.text(f"   {state.frame_label()}")
        imgui.end_main_menu_bar()


#: The font whose glyphs fill in what ImGui's default (ProggyClean, ASCII only) lacks: ΔE2000, θ, λ, ≤, °, ...
#: matplotlib's DejaVu Sans Mono, a dependency already: no font file of our own, nothing downloaded.
FALLBACK_FONT = Path("mpl-data") / "fonts" / "ttf" / "DejaVuSansMono.ttf"


def _fonts(imgui) -> None:
    """
    ImGui's default font with DejaVu Sans Mono merged under it: ASCII keeps the default's look and metrics,
    and the labels' Greek letters and symbols (ΔE2000, θ, ≤) no longer show as '?'. ImGui 1.92 loads the
    merged glyphs on demand (the backend renders textures), so no glyph ranges are listed.
    """
    import importlib.util

    io = imgui.get_io()
    io.fonts.add_font_default()
    spec = importlib.util.find_spec("matplotlib")
    roots = list(spec.submodule_search_locations or []) if spec is not None else []
    for root in roots:
        path = Path(root) / FALLBACK_FONT
        if path.is_file():
            config = imgui.ImFontConfig()
            config.merge_mode = True
            io.fonts.add_font_from_file_ttf(str(path), 0.0, config)  # 0: the default font's size
            return


def _style(imgui, implot) -> None:
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
    implot_style = implot.get_style()
    for colour in (implot.Col_.frame_bg, implot.Col_.plot_bg):
        implot_style.set_color_(colour, imgui.ImVec4(0.0, 0.0, 0.0, 0.0))


def run_app(material_path, preset: str | None = None, *, script=None, report=None, window_size=DEFAULT_WINDOW,
            view_size: int | None = None, is_default: bool = False, more_paths=(), maps: str | None = None) -> int:
    """Open the explorer on ``material_path`` (and ``more_paths``; ``maps``: a map folder on the first); :class:`AppError` when no window can be opened."""
    app = App(material_path, preset, script=script, report=report, window_size=window_size, view_size=view_size,
              is_default=is_default, more_paths=more_paths, maps=maps)
    return app.run()
