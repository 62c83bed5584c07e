"""
The Design window: colours wanted at chosen angles (picked, or read from a strip image) to the structure
of the open mirror, rough layer or film (:func:`explorer.design.design`), found on a worker
thread with its progress shown, so the window keeps drawing; the result becomes the material's values and
its θ strip is drawn under the target strip. Below, the chromaticities a Bragg mirror can reach at one
angle for the current index bounds (Sobol samples of the box), with the spectral locus and the sRGB
triangle: what colours can a Bragg mirror make at all?
"""

from __future__ import annotations

import threading
import time
from dataclasses import replace

import numpy as np

from explorer.app.panels.base import Panel, checkbox_width, flow, record
from explorer.physics import colorimetry
from explorer import design as inverse_design
from explorer.design.media import with_media
from explorer.materials.models import BraggMirrorModel
from explorer.materials.twins import capabilities_of, supporting
from explorer.resources import DEFAULT_MATERIAL

#: The default targets: the colours at these angles of the jewel beetle's green/blue cuticle area
#: (Fourneau et al. 2024, Table 3 (a), smooth, in air), a gradient a mirror is known to make.
DEFAULT_ANGLES = (0.0, 30.0, 60.0)
DEFAULT_STRUCTURE = {"n1": 1.59, "n2": 1.67, "Lambda": 160.0, "delta": 0.51, "N": 8, "nh": 1.0}
#: Columns of the drawn strips (θ from 0 to 90 degrees).
STRIP_COLUMNS = 64
#: The sRGB primaries' chromaticities (IEC 61966-2-1).
SRGB_TRIANGLE = ((0.64, 0.33), (0.30, 0.60), (0.15, 0.06), (0.64, 0.33))
#: Structures sampled for the reachable chromaticities.
REACHABLE_SAMPLES = 2048


def _c(values) -> np.ndarray:
    return np.ascontiguousarray(values, dtype=np.float64).ravel()


def spectral_locus() -> np.ndarray:
    """The chromaticities ``(x, y)`` of the monochromatic colours 380-700 nm, closed by the purple line."""
    cmfs = colorimetry.colour_matching_functions()[20:341]
    xy = cmfs[:, :2] / np.maximum(cmfs.sum(axis=1, keepdims=True), 1e-12)
    return np.vstack([xy, xy[:1]])


def strip_of(targets, columns: int = STRIP_COLUMNS) -> np.ndarray:
    """The target strip: each column the colour of the nearest target angle, ``(columns, 3)`` linear RGB."""
    theta = 90.0 * (np.arange(columns) + 0.5) / columns
    angles = np.array([t.theta_deg for t in targets])
    nearest = np.argmin(np.abs(theta[:, None] - angles[None]), axis=1)
    return np.array([targets[k].rgb for k in nearest])


def _target(theta: float, rgb) -> list:
    """A target row: ``[theta, sRGB picker values (clipped, 8-bit), linear RGB as given]``."""
    rgb = np.asarray(rgb, dtype=np.float64)
    return [float(theta), [float(c) for c in colorimetry.encode_srgb8(rgb) / 255.0], tuple(float(c) for c in rgb)]


def design_request(material, values, n1_air: bool = False) -> tuple[dict, dict]:
    """
    ``(fixed, media)`` of a design from the window, as ``design --fix`` takes them: the indices whose
    ``medium_*`` names a medium held at it, each layer's ``k`` and the disorder held at the material's values
    (``design --fix n2=chitin --fix k2=... --fix sigma=...``), and with ``n1_air`` air layers (``n1 = 1``, no host).
    """
    from explorer.design.media import MEDIUM_PARAMETERS
    from explorer.materials.media import index_value
    from explorer.physics.dispersion import Dispersion

    model = inverse_design.design_model(material.model)
    fixed = {"n1": 1.0, "nh": 0.0} if n1_air and capabilities_of(material).bragg_spectrum else {}
    media = {}
    for name in MEDIUM_PARAMETERS:
        chosen = index_value(values, name) if f"medium_{name}" in values else None
        if isinstance(chosen, Dispersion):
            media[name] = chosen
            fixed.pop(name, None)
    fixed.update({name: float(values[name]) for name in model.held if name in values})
    return fixed, media


class DesignPanel(Panel):
    title = "Design"
    dock = "right_top"

    def __init__(self, app):
        super().__init__(app)
        colours = inverse_design.forward_rgb(BraggMirrorModel.name, DEFAULT_STRUCTURE, DEFAULT_ANGLES)
        self.targets = [_target(theta, rgb) for theta, rgb in zip(DEFAULT_ANGLES, colours)]
        self.strip_path = ""
        self.strip_range = [0.0, 90.0]
        self.fixed_n1_air = False
        # The material's current structure joins the first pass: designing again after a change of the
        # targets starts from the last result.
        self.from_current = True
        # Each press of "design" searches from a fresh first pass (its seed), so pressing again (from the
        # current structure) searches on from the last result.
        self.runs = 0
        self.index_bounds = [1.0, 2.5]
        self.chroma_theta = 0.0
        self._lock = threading.Lock()
        self._thread: threading.Thread | None = None
        self._cancel = False
        self.progress = (0.0, "")
        self.result: inverse_design.DesignResult | None = None
        self.result_strip: np.ndarray | None = None
        self.error = ""
        self.reachable: tuple | None = None  # (theta, bounds, xy)
        self._reachable_thread: threading.Thread | None = None
        self.state.design = {"running": False}

    # -- the targets --------------------------------------------------------------------------------

    def target_list(self) -> list:
        """
        The targets as :class:`explorer.design.Target`: a colour read from a strip (or the default
        gradient) as its linear RGB, which may lie outside sRGB; one picked, as its picker's sRGB.
        """
        import colour

        return [inverse_design.Target(float(theta), tuple(float(c) for c in (
                    linear if linear is not None else colour.cctf_decoding(np.clip(srgb, 0.0, 1.0), function="sRGB"))))
                for theta, srgb, linear in self.targets]

    def _load_strip(self) -> None:
        from explorer.views.images import read_linear_image

        try:
            image = read_linear_image(self.strip_path)
            targets = inverse_design.targets_from_strip(image, self.strip_range[0], self.strip_range[1])
        except (ValueError, inverse_design.DesignError) as error:
            self.error = str(error)
            return
        self.error = ""
        self.targets = [_target(t.theta_deg, t.rgb) for t in targets]

    # -- the worker ---------------------------------------------------------------------------------

    @property
    def running(self) -> bool:
        return self._thread is not None and self._thread.is_alive()

    def _start(self) -> None:
        material = self.state.material
        if self.running or not capabilities_of(material).design:
            return
        ranges = {p.name: (float(p.min), float(p.max)) for p in material.parameters if p.min is not None}
        fixed, media = design_request(material, self.state.values, self.fixed_n1_air)
        targets = self.target_list()
        parameters = inverse_design.design_model(material.model).parameters
        current = {name: float(self.state.values[name]) for name in parameters if name in self.state.values}
        guesses = [current] if self.from_current and len(current) == len(parameters) else []
        self._cancel = False
        self.error = ""
        self.progress = (0.0, "starting")
        seed, self.runs = self.runs, self.runs + 1
        self.state.design = {"running": True, "targets": [[t.theta_deg, list(t.rgb)] for t in targets], "guesses": guesses,
                             "seed": seed}

        def work():
            started = time.perf_counter()
            try:
                result = inverse_design.design(material.model, targets, ranges, fixed, seed=seed, progress=self._progress,
                                               cancelled=lambda: self._cancel, guesses=guesses, media=media)
                theta = 90.0 * (np.arange(STRIP_COLUMNS) + 0.5) / STRIP_COLUMNS
                model = with_media(inverse_design.design_model(material.model), media, natural=True) if media else None
                strip = (model.converged(result.values, np.cos(np.radians(theta))) if model is not None
                         else inverse_design.forward_rgb(material.model, result.values, theta))
                # A medium is reported and applied by its name (as design --fix n2=chitin reports it).
                result = replace(result, values={**result.values, **{k: v.name for k, v in media.items()}})
            except inverse_design.DesignCancelled:
                with self._lock:
                    self.error, self.state.design = "cancelled", {"running": False, "cancelled": True}
                return
            except inverse_design.DesignError as error:
                with self._lock:
                    self.error, self.state.design = str(error), {"running": False, "error": str(error)}
                return
            with self._lock:
                self.result, self.result_strip = result, strip
                self.state.design = {**result.as_json(material.model), "running": False, "guesses": guesses, "seed": seed,
                                     "reachable": result.reachable.tolist(), "wall_seconds": time.perf_counter() - started}
                self._pending_apply = True

        self._pending_apply = False
        self._thread = threading.Thread(target=work, name="design", daemon=True)
        self._thread.start()

    def _progress(self, fraction: float, stage: str) -> None:
        self.progress = (fraction, stage)

    def _apply(self) -> None:
        """The designed structure becomes the material's values (the other parameters kept)."""
        if self.result is None:
            return
        state = self.state
        state.values = state.material.resolve({**state.values, **self.result.values})
        state.preset = None
        state.status = f"Design: median dE2000 {self.result.median_delta_e2000:.2f} in {self.result.seconds:.1f} s"

    # -- the reachable colours ---------------------------------------------------------------------

    def _reachable_request(self) -> None:
        key = (round(self.chroma_theta, 1), tuple(self.index_bounds))
        if (self.reachable is not None and self.reachable[0] == key) or (
                self._reachable_thread is not None and self._reachable_thread.is_alive()):
            return
        lo, hi = sorted(self.index_bounds)
        ranges = {"n1": (lo, hi), "n2": (lo, hi), "Lambda": (50.0, 1500.0), "delta": (0.0, 1.0), "N": (1.0, 1000.0),
                  "nh": (0.0, 0.0)}

        def work():
            xy, _ = inverse_design.reachable_chromaticities(BraggMirrorModel.name, key[0], ranges, fixed={"nh": 0.0},
                                                            samples=REACHABLE_SAMPLES)
            self.reachable = (key, xy)

        self._reachable_thread = threading.Thread(target=work, name="reachable", daemon=True)
        self._reachable_thread.start()

    # -- UI -----------------------------------------------------------------------------------------

    def draw(self, imgui) -> None:
        state = self.state
        designable = capabilities_of(state.material).design
        if not designable:
            imgui.text_wrapped(f"Design works on {', '.join(supporting('design'))}.")
            if imgui.button(f"Open {DEFAULT_MATERIAL.stem}"):
                self.app.reload(DEFAULT_MATERIAL)
            record(state, "design:open")
        imgui.separator_text("targets (theta in degrees, sRGB colour)")
        remove = None
        for k, target in enumerate(self.targets):
            imgui.push_id(f"target{k}")
            imgui.set_next_item_width(90)
            changed, theta = imgui.slider_float("##theta", target[0], 0.0, 89.0, "%.0f deg")
            if changed:
                target[0] = float(theta)
            record(state, f"design:theta_{k}")
            imgui.same_line()
            changed, colour = imgui.color_edit3("##colour", list(target[1]))
            if changed:  # a picked colour replaces the strip's (the picker shows it clipped to sRGB)
                target[1], target[2] = [float(c) for c in colour], None
            record(state, f"design:colour_{k}")
            imgui.same_line()
            if len(self.targets) > 1 and imgui.small_button("x"):
                remove = k
            imgui.pop_id()
        if remove is not None:
            del self.targets[remove]
        if imgui.button("add an angle"):
            last = self.targets[-1]
            self.targets.append([min(last[0] + 15.0, 89.0), list(last[1]), last[2]])
        record(state, "design:add")
        flow(imgui, checkbox_width(imgui, "air layers (n1 = 1)"))  # on the line when it fits: nothing cut at 1280x800
        _, self.fixed_n1_air = imgui.checkbox("air layers (n1 = 1)", self.fixed_n1_air)
        record(state, "design:air")
        flow(imgui, checkbox_width(imgui, "from the current structure"))
        _, self.from_current = imgui.checkbox("from the current structure", self.from_current)
        record(state, "design:from_current")
        imgui.set_next_item_width(imgui.get_content_region_avail().x * 0.5)
        typed, path = imgui.input_text("strip image", self.strip_path, imgui.InputTextFlags_.enter_returns_true)
        self.strip_path = path
        record(state, "design:strip_path")
        imgui.same_line()
        if imgui.button("load strip") or typed:
            self._load_strip()
        record(state, "design:load_strip")
        imgui.set_next_item_width(imgui.get_content_region_avail().x * 0.5)
        _, rng = imgui.input_float2("strip theta range", self.strip_range)
        self.strip_range = [float(v) for v in rng]
        if self.running:
            fraction, stage = self.progress
            imgui.progress_bar(fraction, imgui.ImVec2(-80, 0), stage)
            imgui.same_line()
            if imgui.button("cancel"):
                self._cancel = True
            record(state, "design:cancel")
        else:
            if imgui.button("design") and designable:
                self._start()
            record(state, "design:run")
        with self._lock:
            if getattr(self, "_pending_apply", False):
                self._pending_apply = False
                self._apply()
            result, strip = self.result, self.result_strip
        if self.error:
            imgui.text_colored(imgui.ImVec4(1.0, 0.35, 0.3, 1.0), self.error)
        self._strips(imgui, strip)
        if result is not None:
            unreachable = (~result.reachable).sum()
            imgui.text_wrapped(" ".join(f"{k}={v:.4g}" if isinstance(v, float) else f"{k}={v}" for k, v in result.values.items()))
            imgui.text_wrapped("dE2000 per target: " + ", ".join(f"{d:.2f}" for d in result.delta_e2000)
                               + (f"; {unreachable} not reachable: the closest structure found" if unreachable else ""))
            if unreachable:
                # The search is not exhaustive (docs/design.md): say so, and what can help.
                imgui.text_wrapped("The search can miss thick, high-order stacks: press design again to search on "
                                   "from fresh samples and, with 'from the current structure', from this result.")
        self._chromaticity(imgui)

    def _strips(self, imgui, strip) -> None:
        """The target strip and, under it, the designed structure's (exact colours), θ from 0 to 90 degrees."""
        rows = [("target", strip_of(self.target_list()))]
        if strip is not None:
            rows.append(("designed", strip))
        draw = imgui.get_window_draw_list()
        width = max(imgui.get_content_region_avail().x - 70, 64)
        for label, colours in rows:
            origin = imgui.get_cursor_screen_pos()
            encoded = colorimetry.encode_srgb8(colours)
            step = width / len(colours)
            for i, c in enumerate(encoded):
                colour = imgui.get_color_u32(imgui.ImVec4(c[0] / 255, c[1] / 255, c[2] / 255, 1.0))
                draw.add_rect_filled(imgui.ImVec2(origin.x + i * step, origin.y), imgui.ImVec2(origin.x + (i + 1) * step + 1, origin.y + 18), colour)
            imgui.dummy(imgui.ImVec2(width, 18))
            record(self.state, f"design:strip_{label}")
            imgui.same_line()
            imgui.text(label)

    def _chromaticity(self, imgui) -> None:
        from imgui_bundle import implot

        imgui.separator_text("colours a Bragg mirror can reach")
        imgui.set_next_item_width(imgui.get_content_region_avail().x * 0.4)
        changed, theta = imgui.slider_float("theta##chroma", self.chroma_theta, 0.0, 89.0, "%.0f deg")
        if changed:
            self.chroma_theta = float(theta)
        record(self.state, "design:chroma_theta")
        imgui.same_line()
        imgui.set_next_item_width(imgui.get_content_region_avail().x * 0.6)
        _, bounds = imgui.input_float2("n bounds", self.index_bounds)
        self.index_bounds = [float(np.clip(v, 1.0, 2.5)) for v in bounds]
        if not self.app.dragging:
            self._reachable_request()
        height = max(160.0, min(320.0, imgui.get_content_region_avail().x * 0.9))
        if not implot.begin_plot("chromaticity (CIE 1931 xy)##design", imgui.ImVec2(-1, height)):
            return
        implot.setup_axes("x", "y")
        implot.setup_axes_limits(0.0, 0.8, 0.0, 0.9, implot.Cond_.once)
        locus = spectral_locus()
        implot.plot_line("spectral locus", _c(locus[:, 0]), _c(locus[:, 1]))
        triangle = np.array(SRGB_TRIANGLE)
        implot.plot_line("sRGB", _c(triangle[:, 0]), _c(triangle[:, 1]))
        if self.reachable is not None:
            xy = self.reachable[1]
            implot.plot_scatter("mirrors (n1, n2 in bounds, host n1)", _c(xy[:, 0]), _c(xy[:, 1]),
                                implot.Spec(marker_size=1.5))
        targets = self.target_list()
        xyz = colorimetry.rgb_to_xyz(np.array([t.rgb for t in targets]))
        xy_t = xyz[:, :2] / np.maximum(xyz.sum(axis=1, keepdims=True), 1e-12)
        implot.plot_scatter("targets", _c(xy_t[:, 0]), _c(xy_t[:, 1]), implot.Spec(marker_size=5.0))
        implot.end_plot()
        record(self.state, "design:chromaticity")
