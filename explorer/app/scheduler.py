"""
The GL work of a frame within its budget: which views advance and in what order (the sphere first),
the host's tables built on a worker thread while a slider moves, the env mode's progressive Monte Carlo,
and the display passes that turn the views into the textures ImGui shows.

Views that cost more than a frame are drawn at reduced resolution while a slider moves and refined in
bands afterwards (:class:`explorer.gpu.progressive.ProgressiveView`), so the window stays responsive.
"""

from __future__ import annotations

import concurrent.futures
import time

from explorer.views.env import EnvironmentMap
from explorer.gpu.display import AccumulatedImage, DisplayPass
from explorer.gpu.env import ProgressiveEnvRender
from explorer.gpu.progressive import CostModel, ProgressiveView
from explorer.app.state import AppState

#: Per-frame budget of GL work (ms): ~30 ms of drawing plus the UI's own frame keeps >= 15 fps.
FRAME_BUDGET_MS = 30.0
#: GL budgets (ms) per frame while a slider is dragged: the active view, and each of the others. With the
#: UI (~3 ms), ImGui's drawing (~8 ms), the display pass and the swap on llvmpipe, 12 ms keeps a frame
#: under 33 ms on a quiet 2-core machine (bench --app).
DRAG_BUDGET_MS = 12.0
#: The other views' budget while dragging, unless their panel sets ``drag_budget_ms`` (the Plots and Texture
#: windows, whose views draw from the prefetcher's values and so build no table on the spot).
SIDE_DRAG_BUDGET_MS = 0.0

#: The displayed views the tone map applies to: the sphere's and the Compare window's.
TONEMAPPED_KEYS = ("main", "compare")


class TablePrefetcher:
    """
    The parameter values the sphere shows. While a slider is dragged the host's tables (the tabulated
    method's converged table, a stack's layers) are built on a worker thread as the frame draws, and the
    sphere shows the current values with the model's quick draft tables where it has them (the tabulated
    method's draft table, a stack's 1-nm layer tables; 20-30 ms), else the newest values whose tables are
    ready. Once the slider is released the real tables are built on the spot, so a released slider always
    shows its own values.
    """

    def __init__(self, renderer):
        self.renderer = renderer
        self.ready_values: dict | None = None  # the newest values whose tables are built
        self._future = None
        self._future_values: dict | None = None
        self._executor = None

    def values(self, material, values: dict, dragging: bool) -> dict:
        """The values to draw ``material`` with this frame (``values``, or the newest ready ones while dragging)."""
        if self.renderer.model_ready(material, values) or (dragging and self.renderer.model_drawable(material, values)):
            self.ready_values = dict(values)
            return values
        if dragging and self.ready_values is not None:
            if self._future is not None and self._future.done():
                if self._future.exception() is None:
                    self.ready_values = self._future_values
                self._future = None
            if self._future is None:
                if self._executor is None:
                    self._executor = concurrent.futures.ThreadPoolExecutor(max_workers=1, thread_name_prefix="tables")
                self._future_values = dict(values)
                self._future = self._executor.submit(self._prepare_while_dragging, material, self._future_values)
            return self.ready_values
        if self._future is not None:
            concurrent.futures.wait([self._future])  # its errors resurface in the bindings, with the current values
        try:
            self.renderer.prepare_model(material, values)  # a released slider shows its real tables, not a draft
        except Exception:  # noqa: BLE001 - raised again by the bindings, with the current values
            pass
        self.ready_values = dict(values)
        return values

    def _prepare_while_dragging(self, material, values: dict) -> None:
        """The model's quick draft tables where it has them (the real ones follow on release), else the real ones."""
        if not self.renderer.prepare_draft(material, values):
            self.renderer.prepare_model(material, values)

    def forget(self) -> None:
        """Another material: none of the previous one's values may reach its uniforms."""
        self.ready_values = None

    def shutdown(self) -> None:
        if self._executor is not None:
            self._executor.shutdown(wait=True)


def model_mesh(name: str, cache: dict):
    """The mesh of a Sphere window model (None for the sphere), generated once per session."""
    if name == "sphere":
        return None
    if name not in cache:
        from explorer.views.mesh import SHAPES

        cache[name] = SHAPES[name]()
    return cache[name]


class EnvSphere:
    """
    The env mode: progressive Monte Carlo (:mod:`explorer.gpu.env`) under the chosen environment, turned,
    with or without the environment behind the sphere or mesh; restarted on change, and converged (no more
    samples drawn) once it holds ``state.env_target_spp`` samples per pixel.
    """

    def __init__(self, renderer):
        self.renderer = renderer
        self.environments: dict[str, EnvironmentMap] = {}
        self.meshes: dict = {}
        self.render: ProgressiveEnvRender | None = None
        self.source: AccumulatedImage | None = None
        self._key = None
        self._structure = None
        self.pending = False  # requested this frame: advanced by the scheduler
        self.restarted = False  # the render restarted since its last work: its next work is a first pass
        self.last_work_ms = 0.0  # the GL time of the last work (ms)
        self.last_first_pass = False  # whether that work was a restarted render's first pass

    def environment(self, name: str) -> EnvironmentMap:
        """An environment of :data:`explorer.views.env.ENVIRONMENTS` by name, loaded once."""
        from explorer.views.env import ENVIRONMENTS

        if name not in self.environments:
            self.environments[name] = ENVIRONMENTS[name]()
        return self.environments[name]

    def request(self, state: AppState, size, values: dict | None = None) -> AccumulatedImage:
        """
        The render of ``state``'s material at ``values`` (default ``state.values``; the app passes those of
        :class:`TablePrefetcher`, drawn with draft tables while a slider moves) at ``size``, as a display
        source. Samples drawn with draft tables are dropped once the real tables are ready.
        """
        values = state.values if values is None else values
        ready = self.renderer.model_ready(state.material, values)  # False: draft tables, restarted when real
        key = (id(state.material), tuple(sorted(values.items())), ready, size, tuple(state.camera), tuple(state.light),
               state.environment, state.env_rotation, state.env_background, state.model)
        if self._key != key or self.render is None:
            environment = self.environment(state.environment).rotated(state.env_rotation)
            # Another material (Files > Open, Reload) needs a render of its own: resetting the old one with
            # the new values would bind them to the old material's uniforms. So do another environment,
            # model or size (their textures); a turn of the probe only restarts the samples.
            structure = (size, state.environment, state.env_background, state.model)
            if self.render is None or self._structure != structure or self.render.material is not state.material:
                if self.render is not None:
                    self.render.release()
                self.render = ProgressiveEnvRender(self.renderer, state.material, values, environment, *size,
                                                   mesh=model_mesh(state.model, self.meshes), background=state.env_background)
                self._structure = structure
            else:
                self.render.environment = environment
                self.render.reset(values=values)
            self._key = key
            self.restarted = True
        self.pending = True
        if self.source is None or self.source.render is not self.render:
            self.source = AccumulatedImage(self.render)
        return self.source

    def progress(self, target: int) -> dict:
        """``{"samples", "target", "converged"}``: whole samples per pixel so far, and whether they reach ``target``."""
        samples = 0 if self.render is None else self.render.samples
        return {"samples": samples, "target": int(target), "converged": samples >= target}

    def work(self, budget_ms: float, target: int | None = None) -> None:
        if target is not None and self.render.samples >= target:
            return  # converged: the image stays, nothing more is drawn
        # Bands of rows when one sample costs more than the budget; the display pass divides by the counts.
        start = time.perf_counter()
        self.render.advance(max(0.5 * budget_ms, 5.0))
        self.last_work_ms = (time.perf_counter() - start) * 1e3
        self.last_first_pass, self.restarted = self.restarted, False

    def report(self) -> dict:
        """The env render's last work, for a frame's record (``bench --app``)."""
        render = self.render
        return {"ms": self.last_work_ms, "first_pass": self.last_first_pass,
                "samples": render.samples if render is not None else 0,
                "band_rows": render._band_rows if render is not None else 0}


class Scheduler:
    """The app's views (progressive jobs by name), what is displayed this frame, and the frame's GL work."""

    def __init__(self, renderer):
        self.renderer = renderer
        self.costs = CostModel()
        self.display = DisplayPass(renderer)
        self.prefetcher = TablePrefetcher(renderer)
        self.env = EnvSphere(renderer)
        self.jobs: dict[str, ProgressiveView] = {}
        self._requests: dict = {}  # display key -> (source a, source b or None), drawn after the views advance
        self.drafts: set[str] = set()  # the views shown with draft tables now (the Texture window's while dragging)

    def job(self, name: str) -> ProgressiveView:
        """The progressive view called ``name`` (made on first use)."""
        if name not in self.jobs:
            self.jobs[name] = ProgressiveView(self.renderer, self.costs)
        return self.jobs[name]

    def show(self, key: str, size, a, b=None):
        """The texture that shows ``a`` (and ``b`` right of the middle) under ``key`` once this frame's work is done."""
        self._requests[key] = (a, b)
        return self.display.target(key, size)

    def work(self, state: AppState, panels, dragging: bool) -> float:
        """Advance the visible panels' views within the frame's budget (the sphere first), then display them; ms."""
        start = time.perf_counter()
        budget = FRAME_BUDGET_MS
        order = [(job, getattr(panel, "drag_budget_ms", SIDE_DRAG_BUDGET_MS))
                 for panel in sorted(panels, key=lambda p: p.gl_order) for job in panel.gl_jobs()]
        if state.pending_screenshot and state.mode != "env":
            order.insert(0, (self.job("main"), SIDE_DRAG_BUDGET_MS))
        # While a slider moves the first view (the sphere) gets a preview that fits with the UI's own
        # ~30 ms in a 15 fps frame; the others get what little is left. In the env mode the sphere is the
        # env render: every job is another view (whose tables would be built on the spot), none leads.
        leading = order[0][0] if order and state.mode != "env" else None
        for job, side_budget in order:
            remaining = budget - (time.perf_counter() - start) * 1e3
            if dragging:
                remaining = min(remaining, DRAG_BUDGET_MS) if job is leading else min(remaining, side_budget)
            if remaining <= 0:
                break
            job.work(remaining)
        self.env.last_work_ms, self.env.last_first_pass = 0.0, False
        if self.env.pending and state.mode == "env":
            self.env.work(budget - (time.perf_counter() - start) * 1e3, state.env_target_spp)
            state.env_progress = self.env.progress(state.env_target_spp)
        self.env.pending = False
        for panel in panels:
            panel.after_gl()
        for key, (a, b) in self._requests.items():
            if a.full is not None:
                # The sphere's and Compare's images under the chosen tone map (a radiance view's AgX by default);
                # the strips, slice and texture views show colours as they are.
                tonemap = state.tonemap_for(getattr(a, "view", "env")) if key in TONEMAPPED_KEYS else "none"
                self.display.draw(key, a, b, split=0.5 if b is not None else 2.0, exposure=state.exposure, gamut=state.gamut,
                                  tonemap=tonemap)
        self._requests = {}
        return (time.perf_counter() - start) * 1e3

    def main_report(self) -> dict:
        """The sphere's progress, for a frame's record."""
        main = self.job("main")
        # The other views (Plots, Texture: bench --app's rows of the new views) by job name.
        views = {name: {"size": list(job.size), "generation": job.generation, "complete": job.complete, "has_preview": job.has_preview,
                        "draft": name in self.drafts} for name, job in self.jobs.items() if name != "main"}
        return {"size": list(main.size), "preview": list(main.preview_size), "has_preview": main.has_preview,
                "complete": main.complete, "generation": main.generation, "views": views}
