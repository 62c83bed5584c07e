"""
The Inverse window: lobes at normal incidence (Bati, Barla & Pacanowski 2021) to a stack of
``shaders/layered_lobes.brd``, live. Per lobe a colour (the RGB energy R), a blur (the variance σ), 1 or 2
layers and its base; each lobe's equivalence class is drawn as in the paper's Figures 4, 7, 9, 11, 12
(invalid parts hatched or shaded) with a point to walk along it; the retrieved stack becomes the
sphere's values, and "compare two members" puts two points of one class side by side (Figures 5, 8, 10).

The class point is two numbers per lobe in [0, 1], ``t`` and ``u``, that walk the valid samples of the
class (:func:`explorer.physics.inverse.lobe_class`), so every position of the sliders is a member:
``t`` walks the first free index (a 1-layer lobe's ``eta``, a 2-layer lobe's ``eta_top`` over N_1, a
conductor's place between Eqs. 10 and 9), ``u`` the second (a 2-layer lobe's ``eta`` over N_2 of that
row, or its conductor base's place).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from explorer.app.panels.base import Panel, button_width, checkbox_width, flow, record
from explorer.materials.lobes_model import LayeredLobesModel
from explorer.physics import lobes
from explorer.physics.inverse import InverseError, Lobe, fgd_normal, invert_lobes, lobe_class

#: The material whose parameters the retrieved stacks are (the layered lobes plugin).
MATERIAL = LayeredLobesModel.name
#: Pixels per class sample in the 2-layer plot's texture (the hatching needs a few).
CELL_PX = 5
#: The recomputation period while a widget is dragged (seconds): a 2-layer class costs ~40 ms.
DRAG_PERIOD_S = 0.1
CHANNELS = ((1.0, 0.3, 0.3), (0.3, 0.9, 0.3), (0.35, 0.5, 1.0))


@dataclass
class LobeEdit:
    """One lobe as the panel edits it: ``energy`` (RGB R), ``sigma``, ``layers``, ``base``, and its class point ``t``, ``u``."""

    energy: list = field(default_factory=lambda: [0.1, 0.2, 0.1])
    sigma: float = 0.03
    layers: int = 2
    base: str = "dielectric"
    t: float = 0.5
    u: float = 0.5

    def lobe(self) -> Lobe:
        return Lobe(self.energy, self.sigma, self.layers, self.base)

    def key(self) -> tuple:
        return (tuple(self.energy), self.sigma, self.layers, self.base, self.t, self.u)


def _c(values) -> np.ndarray:
    """An array as ImPlot takes it: 1D, contiguous float64."""
    return np.ascontiguousarray(values, dtype=np.float64).ravel()


def _pick(candidates, f: float):
    """The sample at fraction ``f`` of ``candidates`` (None when there are none)."""
    return None if len(candidates) == 0 else candidates[int(round(np.clip(f, 0.0, 1.0) * (len(candidates) - 1)))]


def class_choice(cls, t: float, u: float) -> dict:
    """The :func:`invert_lobes` choice of the class point ``(t, u)`` (``{}``: the class is empty, the default point)."""
    if cls.kind == "conductor":
        return {"t": float(t)}
    if cls.kind == "dielectric":
        eta = _pick(cls.eta[cls.valid], t)
        return {} if eta is None else {"eta": float(eta)}
    rows = np.flatnonzero(cls.valid if cls.kind == "two_layer_conductor" else cls.valid.any(axis=1))
    i = _pick(rows, t)
    if i is None:
        return {}
    if cls.kind == "two_layer_conductor":
        return {"eta_top": float(cls.eta_top[i]), "t": float(u)}
    j = _pick(np.flatnonzero(cls.valid[i]), u)
    return {"eta_top": float(cls.eta_top[i]), "eta": float(cls.eta[j])}


def nearest_point(cls, x: float, y: float) -> tuple[float, float]:
    """The ``(t, u)`` of a 2-layer class's valid sample nearest to ``(eta_top, eta) = (x, y)`` (the plot's drag point)."""
    rows = np.flatnonzero(cls.valid.any(axis=1))
    cells = np.argwhere(cls.valid)
    d = (cls.eta_top[cells[:, 0]] - x) ** 2 + (cls.eta[cells[:, 1]] - y) ** 2
    i, j = cells[int(np.argmin(d))]
    cols = np.flatnonzero(cls.valid[i])
    row, col = int(np.searchsorted(rows, i)), int(np.searchsorted(cols, j))
    return row / max(len(rows) - 1, 1), col / max(len(cols) - 1, 1)


@dataclass
class Solution:
    """The panel's lobes solved: each lobe's class and choice, the stack (or the first error, one line)."""

    classes: list
    choices: list
    stack: lobes.Stack | None
    error: str = ""


def solve(edits: list[LobeEdit], tir: bool = False, points=None) -> Solution:
    """
    Classes, choices and stack of ``edits`` (top first), each lobe's class under the lobes above as chosen;
    ``points`` overrides the ``(t, u)`` of each lobe (member B of the compare view).
    """
    lobe_list = [e.lobe() for e in edits]
    points = points or [(e.t, e.u) for e in edits]
    classes, choices = [], []
    try:
        for k, (t, u) in enumerate(points, start=1):
            with np.errstate(all="ignore"):  # invalid samples are NaN in the class, by design
                cls = lobe_class(lobe_list, k, choices + [{}] * (len(edits) - k + 1), tir=tir)
            classes.append(cls)
            choices.append(class_choice(cls, t, u))
        stack = invert_lobes(lobe_list, choices, tir=tir)
    except (InverseError, lobes.StackError) as error:
        return Solution(classes, choices, None, str(error).splitlines()[0])
    return Solution(classes, choices, stack)


def material_values(material, stack: lobes.Stack) -> dict:
    """The material's values for ``stack`` (every other parameter at its default, so a stack has one set of values)."""
    from explorer.materials.lobes_model import values_from_stack

    return material.resolve(values_from_stack(stack))


def class_image(cls) -> np.ndarray:
    """
    A 2-layer class as Figure 12 draws it, RGBA8 rows from the top (largest ``eta``): each channel's valid
    region (``tau >= 0``) in its colour, their intersection (the class) light grey, the rest hatched.
    """
    n_top, n = cls.valid.shape
    with np.errstate(invalid="ignore"):
        per_channel = np.isfinite(cls.tau) & (np.nan_to_num(cls.tau, nan=-1.0) >= 0.0)  # (A, B, 3)
    rgba = np.zeros((n, n_top, 4))  # rows: eta, columns: eta_top
    cell = per_channel.transpose(1, 0, 2).astype(float)
    for c, colour in enumerate(CHANNELS):
        rgba[..., :3] += cell[..., c : c + 1] * np.array(colour) * 0.3
        rgba[..., 3] = np.maximum(rgba[..., 3], 0.45 * cell[..., c])
    inside = cls.valid.T
    rgba[inside] = (0.82, 0.82, 0.82, 0.9)
    image = np.repeat(np.repeat(rgba, CELL_PX, axis=0), CELL_PX, axis=1)[::-1]  # row 0: the largest eta
    y, x = np.mgrid[: image.shape[0], : image.shape[1]]
    hatch = ((x + y) % 8 < 2) & ~np.repeat(np.repeat(inside, CELL_PX, axis=0), CELL_PX, axis=1)[::-1]
    image[hatch] = (0.6, 0.6, 0.6, 0.85)
    return np.ascontiguousarray((np.clip(image, 0.0, 1.0) * 255).astype(np.uint8))


class InversePanel(Panel):
    title = "Inverse"
    dock = "right_top"

    def __init__(self, app):
        super().__init__(app)
        self.edits: list[LobeEdit] = [LobeEdit()]
        self.tir = False
        self.member_b: list | None = None  # the (t, u) of each lobe kept as B
        self.solution: Solution | None = None
        self._key = None
        self._applied_key = None  # the inputs last applied to the sphere (the first frame applies nothing)
        self._time = 0.0
        self._generation = 0  # counts the solutions: a class texture is rebuilt for a new one
        self._textures: dict = {}  # lobe -> (generation, texture)

    # -- state ------------------------------------------------------------------------------------

    def _inputs(self) -> tuple:
        return (tuple(e.key() for e in self.edits), self.tir)

    def _update(self) -> None:
        key = self._inputs()
        if key == self._key:
            return
        # While a slider drags, the class and the stack follow every DRAG_PERIOD_S; on release at once.
        if self.app.dragging and time.perf_counter() - self._time < DRAG_PERIOD_S and self.solution is not None:
            return
        self._time = time.perf_counter()
        first = self._key is None
        self._key = key
        self.solution = solve(self.edits, self.tir)
        self._generation += 1
        self._report()
        if not first:
            self._apply()

    def _is_lobes_material(self) -> bool:
        return self.state.material.model == MATERIAL

    def _apply(self) -> None:
        """The retrieved stack becomes the sphere's values (layered_lobes only)."""
        s = self.solution
        if s is None or s.stack is None or not self._is_lobes_material():
            return
        self.state.values = material_values(self.state.material, s.stack)
        self.state.preset = None
        self._applied_key = self._key

    def _report(self) -> None:
        """What a session reports (and a screenshot records) of the panel: the lobes, the choices, the error."""
        s = self.solution
        self.state.inverse = {
            "lobes": [{"R": list(e.energy), "sigma": e.sigma, "layers": e.layers, "base": e.base} for e in self.edits],
            "points": [[e.t, e.u] for e in self.edits], "choices": s.choices, "tir": self.tir, "error": s.error,
        }

    def _open_lobes_material(self) -> None:
        from explorer.resources import builtin_materials

        if self.app.reload(builtin_materials()[MATERIAL]):
            self._apply()

    def _compare(self) -> None:
        """Member A (the current point) and B (the kept one, else the mirrored point) in Compare's two-sets mode."""
        points_b = self.member_b or [(1.0 - e.t, 1.0 - e.u) for e in self.edits]
        b = solve(self.edits, self.tir, points_b)
        if b.stack is None or self.solution.stack is None:
            self.state.status = f"compare: {b.error or self.solution.error}"
            return
        self._apply()
        c = self.state.compare
        c.values_b, c.kind, c.on = material_values(self.state.material, b.stack), "sets", True
        self.state.focus_request = "Compare"
        self.state.status = "Compare: A = current point | B = " + ("the kept point" if self.member_b else "the mirrored point (1 - t, 1 - u)")

    # -- UI ---------------------------------------------------------------------------------------

    def draw(self, imgui) -> None:
        state = self.state
        if not self._is_lobes_material():
            imgui.text_wrapped(f"The stacks retrieved here are shaders/{MATERIAL}.brd's parameters.")
            if imgui.button(f"Open {MATERIAL}"):
                self._open_lobes_material()
            record(state, "inverse:open")
        remove = None
        for k, edit in enumerate(self.edits, start=1):
            imgui.push_id(f"lobe{k}")
            imgui.separator_text(f"lobe {k}" + (" (top)" if k == 1 and len(self.edits) > 1 else ""))
            if len(self.edits) > 1:
                imgui.same_line()
                if imgui.small_button("remove"):
                    remove = k - 1
            self._lobe_widgets(imgui, k, edit, bottom=k == len(self.edits))
            imgui.pop_id()
        if remove is not None:
            del self.edits[remove]
            self.member_b = None
        if len(self.edits) < lobes.MAX_INTERFACES and imgui.button("add a lobe below"):
            self.edits[-1].base = "dielectric"  # only the bottom lobe may sit on a conductor
            self.edits.append(LobeEdit(energy=[0.12, 0.08, 0.04], sigma=0.05, layers=1))
            self.member_b = None
        record(state, "inverse:add")
        flow(imgui, checkbox_width(imgui, "tir"))  # on the line when it fits: nothing cut at 1280x800
        _, self.tir = imgui.checkbox("tir", self.tir)
        self._update()
        s = self.solution
        if s.error:
            imgui.push_text_wrap_pos(0.0)
            imgui.text_colored(imgui.ImVec4(1.0, 0.35, 0.3, 1.0), s.error)
            imgui.pop_text_wrap_pos()
        if imgui.button("apply") and s.stack is not None:
            self._apply()
        record(state, "inverse:apply")
        flow(imgui, button_width(imgui, "keep as B"))
        if imgui.button("keep as B"):
            self.member_b = [(e.t, e.u) for e in self.edits]
        record(state, "inverse:keep_b")
        flow(imgui, button_width(imgui, "compare two members"))
        if imgui.button("compare two members") and self._is_lobes_material():  # A = this point | B
            self._compare()
        record(state, "inverse:compare")
        for k, cls in enumerate(s.classes, start=1):
            self._plot(imgui, k, cls, s)
        self._stack_line(imgui, s)

    def _lobe_widgets(self, imgui, k: int, edit: LobeEdit, bottom: bool) -> None:
        state = self.state
        imgui.text("R (energy at normal incidence)")  # above its fields: beside them it was cut at 1280x800
        imgui.set_next_item_width(-1)
        changed, colour = imgui.color_edit3("##R", list(edit.energy), imgui.ColorEditFlags_.float)
        if changed:
            edit.energy = [float(c) for c in colour]
        record(state, f"inverse:R_colour_{k}")
        imgui.set_next_item_width(imgui.get_content_region_avail().x * 0.55)
        typed, text = imgui.input_text("R (r,g,b)", ",".join(f"{c:.4g}" for c in edit.energy),
                                       imgui.InputTextFlags_.enter_returns_true | imgui.InputTextFlags_.auto_select_all)
        record(state, f"inverse:R_{k}")
        if typed:
            try:
                parts = [float(p) for p in text.replace(" ", "").split(",")]
                if len(parts) not in (1, 3) or not all(np.isfinite(parts)):
                    raise ValueError
                edit.energy = parts * 3 if len(parts) == 1 else parts
            except ValueError:
                state.status = f"lobe {k}: R is one number or r,g,b, not {text!r}"
        imgui.set_next_item_width(imgui.get_content_region_avail().x * 0.45)
        changed, sigma = imgui.slider_float("blur sigma", edit.sigma, 0.0, 0.2, "%.4f", imgui.SliderFlags_.no_input)
        record(state, f"inverse:sigma_{k}")
        if changed:
            edit.sigma = float(sigma)
        imgui.same_line()
        imgui.set_next_item_width(-1)
        typed, text = imgui.input_text("##sigma", f"{edit.sigma:g}", imgui.InputTextFlags_.enter_returns_true | imgui.InputTextFlags_.auto_select_all)
        record(state, f"inverse:sigma_typed_{k}")
        if typed:
            try:
                edit.sigma = max(float(text), 0.0)
            except ValueError:
                state.status = f"lobe {k}: sigma is a number, not {text!r}"
        for layers in (1, 2):
            if imgui.radio_button(f"{layers} layer{'s' if layers == 2 else ''}", edit.layers == layers):
                edit.layers = layers
            record(state, f"inverse:layers_{k}:{layers}")
            imgui.same_line()
        if bottom:
            conductor = edit.base == "conductor"
            imgui.new_line()
            flow(imgui, checkbox_width(imgui, "conductor base"))
            changed, conductor = imgui.checkbox("conductor base", conductor)
            if changed:
                edit.base = "conductor" if conductor else "dielectric"
            record(state, f"inverse:conductor_{k}")
        else:
            imgui.new_line()
        names = {"conductor": ("t (conductor eta)", None), "dielectric": ("t (eta)", None),
                 "two_layer": ("t (eta_top over N1)", "u (eta over N2)"),
                 "two_layer_conductor": ("t (eta_top over N1)", "u (conductor eta)")}
        kind = ("two_layer_conductor" if edit.base == "conductor" else "two_layer") if edit.layers == 2 else edit.base
        t_name, u_name = names[kind]
        imgui.set_next_item_width(imgui.get_content_region_avail().x * 0.55)
        changed, t = imgui.slider_float(t_name, edit.t, 0.0, 1.0, "%.3f", imgui.SliderFlags_.no_input)
        record(state, f"inverse:t_{k}")
        if changed:
            edit.t = float(t)
        if u_name:
            imgui.set_next_item_width(imgui.get_content_region_avail().x * 0.55)
            changed, u = imgui.slider_float(u_name, edit.u, 0.0, 1.0, "%.3f", imgui.SliderFlags_.no_input)
            record(state, f"inverse:u_{k}")
            if changed:
                edit.u = float(u)

    @staticmethod
    def _stack_line(imgui, s: Solution) -> None:
        if s.stack is None:
            return
        parts = []
        for i in range(1, s.stack.count + 1):
            eta = s.stack.eta[i]
            text = f"eta {eta.mean():.3f}" if np.ptp(eta) == 0 else "eta " + ",".join(f"{v:.3f}" for v in eta)
            if s.stack.conductor and i == s.stack.count:
                text += " kappa " + ",".join(f"{v:.3f}" for v in s.stack.kappa[i])
            text += f" alpha {s.stack.alpha[i]:.3f}"
            if i < s.stack.count and np.any(s.stack.tau[i] > 0):
                text += " tau " + ",".join(f"{v:.3f}" for v in s.stack.tau[i])
            parts.append(f"{i}: {text}")
        imgui.text_wrapped("stack (top first) " + "; ".join(parts))

    # -- the class plots (Figures 4, 7, 9, 11, 12) ------------------------------------------------

    def _plot(self, imgui, k: int, cls, s: Solution) -> None:
        from imgui_bundle import implot

        edit, choice = self.edits[k - 1], s.choices[k - 1]
        height = max(160.0, min(300.0, imgui.get_content_region_avail().x * 0.8))
        if not implot.begin_plot(f"lobe {k}: class##class{k}", imgui.ImVec2(-1, height), implot.Flags_.no_legend):
            return
        always = implot.Cond_.always  # the class changes with the lobe: the axes follow it
        grey = implot.Spec(fill_color=imgui.ImVec4(0.6, 0.6, 0.6, 0.3))
        point = implot.Spec(marker_size=5.0, marker_fill_color=imgui.ImVec4(1, 1, 0, 1), marker_line_color=imgui.ImVec4(1, 1, 0, 1))
        if cls.kind == "two_layer":
            caption = "light grey: the class (tau >= 0 on every channel); red, green, blue: one channel's; hatched: invalid. Drag the yellow point, or walk t and u."
            implot.setup_axes("eta_top (eta_1)", "eta (eta_2)")
            implot.setup_axes_limits(1.0, 4.0, 1.0, 4.0, always)
            texture = self._class_texture(k, cls)
            implot.plot_image("class", imgui.ImTextureRef(texture.glo), implot.Point(1.0, 1.0), implot.Point(4.0, 4.0))
            if choice:
                changed, x, y, *_ = implot.drag_point(k, choice["eta_top"], choice["eta"], imgui.ImVec4(1, 1, 0, 1), 6.0)
                if changed and cls.valid.any():
                    edit.t, edit.u = nearest_point(cls, x, y)
        elif cls.kind == "two_layer_conductor":
            caption = "the bottom roughness against eta_top; shaded: no conductor base reaches the lobe (outside N1). The base's own class: u."
            alpha = np.nan_to_num(cls.alpha, nan=0.0)
            top = float(max(alpha[cls.valid].max() if cls.valid.any() else 0.0, 1e-3)) * 1.3
            implot.setup_axes("eta_top (eta_1)", "bottom alpha")
            implot.setup_axes_limits(1.0, 4.0, 0.0, top, always)
            implot.plot_shaded("outside N1", _c(cls.eta_top), _c(np.where(cls.valid, 0.0, top)), 0.0, grey)
            implot.plot_line("alpha", _c(cls.eta_top), _c(np.where(cls.valid, alpha, np.nan)), implot.Spec(line_weight=2.0))
            if choice:
                x = np.array([choice["eta_top"]])
                implot.plot_scatter("point", _c(x), _c(np.interp(x, cls.eta_top, alpha)), point)
        elif cls.kind == "conductor":
            caption = "kappa(eta) per channel (Fig. 4b): thick where valid (Eqs. 10 and 9, kappa >= eta), shaded below where not; dots: the point t."
            kappa_valid = cls.kappa[cls.valid]
            top = float(kappa_valid.max() * 1.2) if kappa_valid.size else 1.0
            implot.setup_axes("eta", "kappa")
            implot.setup_axes_limits(0.0, float(np.nanmax(cls.eta)), 0.0, top, always)
            for c, colour in enumerate(CHANNELS):
                eta, kappa, valid = cls.eta[:, c], cls.kappa[:, c], cls.valid[:, c]
                implot.plot_shaded(f"{'RGB'[c]} invalid", _c(eta), _c(np.where(valid, np.nan, np.nan_to_num(kappa))), 0.0, grey)
                implot.plot_line(f"{'RGB'[c]} (all)", _c(eta), _c(kappa), implot.Spec(line_color=imgui.ImVec4(*colour, 0.45)))
                implot.plot_line(f"{'RGB'[c]} valid", _c(eta), _c(np.where(valid, kappa, np.nan)),
                                 implot.Spec(line_color=imgui.ImVec4(*colour, 1.0), line_weight=3.0))
            if s.stack is not None:
                implot.plot_scatter("point", _c(s.stack.eta[s.stack.count]), _c(s.stack.kappa[s.stack.count]), point)
        elif k > 1:
            caption = "tau above the interface per channel against its eta (Algorithm 4); shaded: tau < 0 on some channel (invalid)."
            tau = np.nan_to_num(cls.tau, nan=0.0, posinf=0.0, neginf=0.0)
            low, top = min(float(tau.min()), 0.0), float(max(tau.max(), 0.1))
            implot.setup_axes("eta", "tau above")
            implot.setup_axes_limits(1.0, 4.0, low, top, always)
            implot.plot_shaded("invalid (tau < 0)", _c(cls.eta), _c(np.where(cls.valid, np.nan, top)), low, grey)
            for c, colour in enumerate(CHANNELS):
                implot.plot_line(f"tau {'RGB'[c]}", _c(cls.eta), _c(tau[:, c]), implot.Spec(line_color=imgui.ImVec4(*colour, 1.0)))
            if choice:
                implot.plot_scatter("point", _c([choice["eta"]]), _c([np.interp(choice["eta"], cls.eta, tau.max(axis=1))]), point)
        else:
            caption = "in air the class is Eq. 7's roots, FGD(eta) = R (Fig. 4a at eta_0 = 1); shaded: eta < 1, eta > 4."
            top = max(0.6, 1.2 * max(edit.energy))
            implot.setup_axes("eta", "energy at normal incidence")
            implot.setup_axes_limits(0.25, 5.0, 0.0, top, always)
            eta = np.linspace(0.25, 5.0, 200)
            fgd = fgd_normal(float(lobes.roughness_from_variance(edit.sigma)), eta)
            implot.plot_shaded("eta < 1", _c([0.25, 1.0]), _c([top, top]), 0.0, grey)
            implot.plot_shaded("eta > 4", _c([4.0, 5.0]), _c([top, top]), 0.0, grey)
            implot.plot_line("FGD(eta)", _c(eta), _c(fgd))
            implot.plot_inf_lines("R", _c([max(edit.energy)]), implot.Spec(flags=implot.InfLinesFlags_.horizontal))
            if choice:
                implot.plot_scatter("point", _c([choice["eta"]]), _c([max(edit.energy)]), point)
        implot.end_plot()
        record(self.state, f"inverse:plot_{k}")
        imgui.text_wrapped(caption)

    def _class_texture(self, k: int, cls):
        """Lobe ``k``'s 2-layer class as a texture, rebuilt for each new solution."""
        generation, texture = self._textures.get(k, (None, None))
        if generation == self._generation:
            return texture
        image = class_image(cls)
        texture = self.app.renderer.resources.replace(texture, image, dtype="f1", origin="class plot")
        self._textures[k] = (self._generation, texture)
        return texture
