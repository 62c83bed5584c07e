"""
Everything the explorer window shows or was asked for, in one dataclass: the material and its values,
the view settings, the comparison, the requests the UI or a script makes (screenshots, focus, quit),
and what a session reports. The panels, the scheduler and the script robot read and write it.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from explorer.views.fill import DEFAULT_FILL

from explorer.materials.methods import opening_values
from explorer.materials.brd import Material

VIEW_SIZES = (128, 256, 512, 1024)
#: The env mode's "converged" sample counts (samples per pixel), its default the second.
ENV_TARGETS = (64, 256, 1024, 4096)
#: The Sphere window's models: the sphere, or a generated mesh (explorer.views.mesh.SHAPES) in the lit and env modes.
SPHERE_MODELS = ("sphere", "teapot", "cube", "torus")
DEFAULT_VIEW_SIZE = 512
#: The sphere's side when it follows its window (``AppState.view_size_auto``): a multiple of this step
#: (a dragged dock splitter re-renders it every step, not every pixel), within these bounds.
AUTO_VIEW_STEP = 32
AUTO_VIEW_BOUNDS = (128, 1024)
MODES = ("lit", "sphere", "env")
#: The loaded materials' colours in the plots (matplotlib's tab10, the first six), in loading order.
MATERIAL_COLOURS = ((0.12, 0.47, 0.71), (1.0, 0.5, 0.05), (0.17, 0.63, 0.17), (0.84, 0.15, 0.16), (0.58, 0.4, 0.74),
                    (0.55, 0.34, 0.29))


def auto_view_size(width: float, height: float) -> int:
    """The sphere's side for a window region of ``width`` x ``height`` pixels (see :data:`AUTO_VIEW_STEP`)."""
    side = int(min(width, height)) // AUTO_VIEW_STEP * AUTO_VIEW_STEP
    return min(max(side, AUTO_VIEW_BOUNDS[0]), AUTO_VIEW_BOUNDS[1])


def has_reflectance(material: Material) -> bool:
    """Whether the material defines ``reflectance(cos_theta)`` (the sphere and gradient views need it)."""
    return re.search(r"\bvec3\s+reflectance\s*\(", material.shader) is not None


def initial_values(material: Material, preset: str | None, is_default: bool) -> dict:
    """The values the app starts with: defaults, a Bragg material's tabulated method, a preset."""
    overrides: dict = dict(opening_values(material))  # as render, export and albedo open it
    if preset is not None:
        from explorer.materials.presets import presets_for

        overrides.update(presets_for(material.path).get(preset).values)
    return material.resolve(overrides)


@dataclass
class CompareState:
    """
    The Compare window: two methods (``a``, ``b``), two parameter sets (current | ``values_b``) or two
    loaded materials (the selected one | the entry ``material_b``).
    """

    values_b: dict
    on: bool = False
    kind: str = "methods"  # or "sets", "materials"
    a: int = 0
    b: int = 4
    size: list = field(default_factory=list)  # the pair's resolution, fitted to the window (reported)
    material_b: int = 0  # an index in AppState.materials
    heat: bool = False  # the ΔE2000 heat-map instead of the split sphere


@dataclass
class MaterialEntry:
    """One loaded material: its file, values (the selected one's are ``AppState.values``), plot colour, visibility."""

    path: Path
    material: Material
    values: dict
    colour: tuple
    visible: bool = True
    polar_log: bool = False  # the Polar window's scale of this material's curve (explorer.app.data.polar_radius)
    polar_normalise: bool = False

    @property
    def name(self) -> str:
        return self.path.name

    def report(self) -> dict:
        return {"path": str(self.path), "visible": self.visible, "colour": list(self.colour),
                "polar": {"log": self.polar_log, "normalise": self.polar_normalise},
                "values": {k: list(v) if isinstance(v, tuple) else v for k, v in self.values.items()}}


@dataclass
class AppState:
    """The window's state (see the module's docstring); ``light`` and ``camera`` in degrees."""

    material_path: Path
    material: Material
    values: dict
    compare: CompareState
    preset: str | None = None
    view_size: int = DEFAULT_VIEW_SIZE
    view_size_auto: bool = False  # the sphere's side follows its window (auto_view_size)
    materials: list = field(default_factory=list)  # MaterialEntry, in loading order; materials[selected] is shown
    selected: int = 0
    slice_phi_d: float = 90.0  # the Slice window's phi_d (degrees)
    slice_gamma: float = 2.2
    slice_chroma: bool = False
    slice_report: dict | None = None  # what the Slice window shows (phi_d, gamma, chroma, its image's range)
    dialog_answers: list = field(default_factory=list)  # scripted answers to File > Open... (lists of paths)
    show_about: bool = False
    first_screen: list = field(default_factory=list)  # the windows drawn on the first screen (reported)
    plotted_log: dict = field(default_factory=dict)  # script mark -> plotted, at its first frame (reported)
    plotted: dict = field(default_factory=dict)  # plot window -> the materials it drew curves of (reported)
    show_controls: bool = False
    mode: str = "lit"  # one of MODES
    light: list = field(default_factory=lambda: [45.0, 0.0])  # theta, phi (explorer.views.geometry.DEFAULT_LIGHT)
    camera: list = field(default_factory=lambda: [0.0, 0.0])  # yaw, pitch: turns the light relative to the view
    zoom: float = 1.0
    exposure: float = 1.0
    tonemap: str = "auto"  # "auto" (explorer.views.tonemap.default_tonemap of the view) or one of TONEMAPS
    fill: float = DEFAULT_FILL  # the lit view's environment fill (explorer.views.fill), 0: the light alone
    # The env mode (explorer.app.scheduler.EnvSphere): its environment (a name of explorer.views.env.ENVIRONMENTS),
    # the probe's turn (degrees), the environment behind the object, the samples per pixel that make it
    # converged (no more are drawn), and its progress (samples, target, converged) for the status and report.
    environment: str = "sky"
    env_rotation: float = 0.0
    env_background: bool = False
    env_target_spp: int = ENV_TARGETS[1]
    env_progress: dict = field(default_factory=dict)
    # "Switch model": the sphere or a mesh of SPHERE_MODELS (lit and env; the white-furnace sphere stays a sphere).
    model: str = "sphere"
    gamut: bool = False
    mean_delta_e: float | None = None
    accuracy: str = ""  # the Parameters window's accuracy badge (a Bragg mirror's method vs the converged table)
    spectrum_theta: float = 0.0
    spectrum_show: dict = field(default_factory=lambda: dict.fromkeys(
        ("s", "p", "average", "envelope", "gaps", "landmarks", "boxes"), True))
    file_path: str = "params.json"
    status: str = ""
    inverse: dict | None = None  # the Inverse window's lobes, class points and error (reported with screenshots)
    design: dict | None = None  # the Design window's targets, progress and result (reported)
    plots: dict | None = None  # the Plots window's plot, settings, light and plotted values (reported)
    texture_view: dict | None = None  # the Texture window's settings and its image's mean RGB (reported)
    maps_folder: str = ""  # structure maps the Texture window draws on the mirror (open --maps; "" the grey image)
    error: str = ""  # the material's load/compile error, shown in red; the last good shader stays
    # Requests, served when the frame allows.
    pending_screenshot: str | None = None
    active_view: str = "sphere"  # the view in front, that F12 saves: "sphere" (the Sphere window) or "compare"
    focused_view: str = "Sphere"  # the last of the Sphere and Compare windows focused (both undocked: it is in front)
    strip_rows: list = field(default_factory=list)  # the Strips window's rows, top to bottom (reported)
    polar_report: dict | None = None  # the Polar window's curves' peaks, scales and axes (reported)
    spectrum_legend: str = ""  # where the Spectrum plot's legend is (reported)
    pending_window_shot: str | None = None
    pending_slice_save: str | None = None
    focus_request: str | None = None
    quit: bool = False
    # This frame's UI.
    orbit_drag: bool = False
    visible: set = field(default_factory=set)  # titles of the windows drawn this frame
    rects: dict = field(default_factory=dict)  # label -> screen rectangle of the item (for scripted input)
    script_target: str | None = None  # the label scripted input is aiming at: scrolled into view when hidden
    hidden: set = field(default_factory=set)  # labels of recorded items outside their panel's visible part
    # What a session reports.
    frame_times: list = field(default_factory=list)
    screenshots: list = field(default_factory=list)
    screenshot_info: dict = field(default_factory=dict)  # per screenshot: material, view, values, env samples

    def sync_selected(self) -> None:
        """The selected entry holds the values being edited (the plots of every visible entry read them there)."""
        if self.materials:
            entry = self.materials[self.selected]
            entry.material, entry.path, entry.values = self.material, self.material_path, self.values

    def select(self, index: int) -> None:
        """Show ``materials[index]`` in the sphere views and the Parameters window."""
        self.sync_selected()
        self.show_entry(index)

    def show_entry(self, index: int) -> None:
        """Show ``materials[index]`` without saving the shown values first (the shown entry was closed)."""
        self.selected = index
        entry = self.materials[index]
        self.material, self.material_path, self.values = entry.material, entry.path, entry.values
        self.compare.values_b = dict(entry.values)
        self.preset = None

    def visible_entries(self) -> list:
        """The materials the plots overlay (the selected one's values current)."""
        self.sync_selected()
        return [entry for entry in self.materials if entry.visible]

    def next_colour(self) -> tuple:
        used = {entry.colour for entry in self.materials}
        free = [c for c in MATERIAL_COLOURS if c not in used]
        return free[0] if free else MATERIAL_COLOURS[len(self.materials) % len(MATERIAL_COLOURS)]

    def view_settings(self) -> dict:
        """What a parameter set saves beside the values so that ``render --params`` shows this view."""
        from explorer.views.mirror import is_mirror_only

        # The environment (its name: render --env takes it) and its turn, where the view shows one: the env
        # mode, and a smooth mirror in the lit mode.
        reflects = self.mode == "env" or (self.main_view() == "lit" and is_mirror_only(self.material))
        return {"view": "env" if self.mode == "env" else self.main_view(), "light": list(self.light),
                "camera": list(self.camera), "exposure": float(self.exposure),
                "tonemap": self.tonemap_for("env" if self.mode == "env" else self.main_view()),
                "fill": float(self.fill) if self.main_view() == "lit" and self.mode != "env" else None,
                "environment": self.environment if reflects else None, "env_rotation": float(self.env_rotation) if reflects and self.env_rotation else None}

    def lit_uniforms(self, material, view: str) -> dict:
        """The lit view's environment fill for ``material`` (none for a smooth mirror, nor in other views)."""
        from explorer.views.fill import has_fill

        return {"fill": float(self.fill)} if view.rsplit("/", 1)[-1] == "lit" and has_fill(material) else {}

    def tonemap_for(self, view: str) -> str:
        """The display curve of ``view`` (a template such as ``mesh/lit`` counts as its view): the chosen one, or its default."""
        from explorer.views.tonemap import default_tonemap

        return default_tonemap(view.rsplit("/", 1)[-1]) if self.tonemap == "auto" else self.tonemap

    def main_view(self) -> str:
        """The sphere's view: ``sphere`` when chosen and the material has a reflectance, else ``lit``."""
        return "sphere" if self.mode == "sphere" and has_reflectance(self.material) else "lit"

    def frame_label(self) -> str:
        """The median frame time of the last 30 frames, for the menu bar and the panels."""
        recent = [f["ms"] for f in self.frame_times[-30:]]
        if not recent:
            return ""
        ms = float(np.median(recent))
        return f"frame {ms:.1f} ms ({1e3 / max(ms, 1e-3):.0f} fps)"

    def json_values(self) -> dict:
        """The values as JSON has them (colours as lists)."""
        return {k: list(v) if isinstance(v, tuple) else v for k, v in self.values.items()}
