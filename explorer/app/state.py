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

from explorer.materials.methods import BraggMethod
from explorer.materials.brd import Material

VIEW_SIZES = (128, 256, 512, 1024)
DEFAULT_VIEW_SIZE = 512
MODES = ("lit", "sphere", "env")


def has_reflectance(material: Material) -> bool:
    """Whether the material defines ``reflectance(cos_theta)`` (the sphere and gradient views need it)."""
    return re.search(r"\bvec3\s+reflectance\s*\(", material.shader) is not None


def initial_values(material: Material, preset: str | None, is_default: bool) -> dict:
    """The values the app starts with: defaults, the default material's tabulated method, a preset."""
    overrides: dict = {}
    if is_default and any(p.name == "method" for p in material.parameters):
        overrides["method"] = int(BraggMethod.TABULATED)  # the default material opens on its fastest exact method
    if preset is not None:
        from explorer.materials.presets import presets_for

        overrides.update(presets_for(material.path).get(preset).values)
    return material.resolve(overrides)


@dataclass
class CompareState:
    """The Compare window: two methods (``a``, ``b``) or two parameter sets (current | ``values_b``)."""

    values_b: dict
    on: bool = False
    kind: str = "methods"  # or "sets"
    a: int = 0
    b: int = 4
    heat: bool = False  # the ΔE2000 heat-map instead of the split sphere


@dataclass
class AppState:
    """The window's state (see the module's docstring); ``light`` and ``camera`` in degrees."""

    material_path: Path
    material: Material
    values: dict
    compare: CompareState
    preset: str | None = None
    view_size: int = DEFAULT_VIEW_SIZE
    mode: str = "lit"  # one of MODES
    light: list = field(default_factory=lambda: [45.0, 0.0])  # theta, phi (explorer.views.geometry.DEFAULT_LIGHT)
    camera: list = field(default_factory=lambda: [0.0, 0.0])  # yaw, pitch: turns the light relative to the view
    zoom: float = 1.0
    exposure: float = 1.0
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
    error: str = ""  # the material's load/compile error, shown in red; the last good shader stays
    # Requests, served when the frame allows.
    pending_screenshot: str | None = None
    pending_window_shot: str | None = None
    focus_request: str | None = None
    quit: bool = False
    # This frame's UI.
    orbit_drag: bool = False
    visible: set = field(default_factory=set)  # titles of the windows drawn this frame
    rects: dict = field(default_factory=dict)  # label -> screen rectangle of the item (for scripted input)
    # What a session reports.
    frame_times: list = field(default_factory=list)
    screenshots: list = field(default_factory=list)
    screenshot_info: dict = field(default_factory=dict)  # per screenshot: material, view, values, env samples

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
