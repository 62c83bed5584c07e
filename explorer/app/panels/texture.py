"""
The Texture window: the textured view (:mod:`explorer.views.surface_texture`) of a material that declares
``# texture:``: a thin film's D_inc over a range, or a Bragg mirror's Lambda and/or delta (supplemental
Figure 7), from a grey image (the shipped noise by default), lit by the app's light.
"""

from __future__ import annotations

import numpy as np

from explorer.app.camera import light_vector
from explorer.app.panels.base import Panel, record, show_image
from explorer.errors import LocatedError
from explorer.resources import DEFAULT_TEXTURE
from explorer.views.surface_texture import MAPPINGS, TEXTURE_KINDS, BraggTexture
from explorer.views.thickness import DEFAULT_DINC_RANGE, DINC_MAX, ThicknessTexture

TEXTURE_VIEW_SIZE = 256


class TexturePanel(Panel):
    title = "Texture"
    dock = "right_top"
    gl_order = 7

    def __init__(self, app):
        super().__init__(app)
        self.path = str(DEFAULT_TEXTURE)
        self.mapping = "both"
        self.dinc_range = list(DEFAULT_DINC_RANGE)
        self.message = ""
        self._surface = None
        self._surface_key = None
        self._arguments = None
        self._arguments_key = None
        self._generation = -1
        self._pending = None  # (key, values, future) of the arguments being built on the worker thread
        self._executor = None

    def _texture(self, kind: str):
        """The surface texture of the current settings (loaded again only when they change)."""
        key = (kind, self.path, self.mapping, tuple(self.dinc_range))
        if key != self._surface_key:
            self._surface_key = key
            try:
                if kind == "bragg":
                    self._surface = BraggTexture.from_file(self.path, self.mapping)
                else:
                    self._surface = ThicknessTexture.from_file(self.path, tuple(sorted(self.dinc_range)))
                self.message = ""
            except LocatedError as error:
                self._surface, self.message = None, str(error)
        return self._surface

    def draw(self, imgui) -> None:
        state = self.state
        kind = state.material.texture
        if kind not in TEXTURE_KINDS:
            imgui.text_wrapped(f"this material declares no '# texture: {'|'.join(TEXTURE_KINDS)}' (thin_film and bragg_mirror do)")
            return
        _, self.path = imgui.input_text("texture (grey image)", self.path)
        if kind == "bragg":
            if imgui.begin_combo("mapping", self.mapping):
                for name in MAPPINGS:
                    clicked, _ = imgui.selectable(name, name == self.mapping)
                    record(state, f"mapping:{name}")
                    if clicked:
                        self.mapping = name
                imgui.end_combo()
            record(state, "mapping_combo")
            imgui.text_wrapped("Lambda (0.5 + 0.5 T), delta^T (supplemental Fig. 7)")
        else:
            _, self.dinc_range = imgui.slider_float2("D_inc range (nm)", self.dinc_range, 0.0, DINC_MAX, "%.0f")
            self.dinc_range = list(self.dinc_range)
        surface = self._texture(kind)
        if self.message:
            imgui.text_colored(imgui.ImVec4(1.0, 0.35, 0.3, 1.0), self.message)
        if surface is None:
            return
        size = (TEXTURE_VIEW_SIZE, TEXTURE_VIEW_SIZE)
        job = self.scheduler.job("textured")
        values = self.scheduler.prefetcher.values(state.material, state.values, self.app.dragging)
        key = (id(state.material), tuple(sorted((k, str(v)) for k, v in values.items())), self._surface_key)
        # The textured mirror's tabulated table takes seconds: built on a worker thread once a slider is
        # released, the last image shown meanwhile.
        if self._pending is not None and self._pending[2].done():
            pending_key, pending_values, future = self._pending
            self._pending = None
            try:
                self._arguments, self._arguments_key, self._values = future.result(), pending_key, pending_values
            except Exception as error:  # noqa: BLE001 - a material's own error, shown in the window
                self.message = f"{type(error).__name__}: {error}"
        wanted = key != self._arguments_key and not (self.app.dragging and self._arguments is not None)
        if wanted and (self._pending is None or self._pending[0] != key):
            import concurrent.futures

            if self._executor is None:
                self._executor = concurrent.futures.ThreadPoolExecutor(max_workers=1, thread_name_prefix="texture")
            self._pending = (key, dict(values), self._executor.submit(surface.gl_arguments, state.material, dict(values), *size))
        if self._arguments is None:
            imgui.text("building the texture's tables…")
            return
        job.request(state.material, self._values, "textured", size, light=light_vector(state.light, state.camera),
                    uniforms=self._arguments["uniforms"], inputs=self._arguments["inputs"], dragging=self.app.dragging)
        show_image(state, self.scheduler.show("textured", size, job), size, "textured_image")
        imgui.text(("done" if job.complete else f"refining {100 * job.progress:.0f}%") + (f"  {job.error}" if job.error else ""))
        if not (job.complete and self._arguments_key == key):  # a new image on its way (scripts wait_for it)
            state.texture_view = {"running": True}
        elif job.generation != self._generation or not state.texture_view or state.texture_view.get("running"):
            self._generation = job.generation
            image = job.read()
            state.texture_view = {"kind": kind, "path": self.path, "mapping": self.mapping, "dinc_range": list(self.dinc_range),
                                  "values": {k: (list(v) if isinstance(v, tuple) else v) for k, v in self._values.items()},
                                  "light": list(light_vector(state.light, state.camera)), "size": list(size),
                                  "mean_rgb": np.asarray(image, np.float64).reshape(-1, 3).mean(axis=0).tolist()}

    def gl_jobs(self) -> list:
        return [self.scheduler.job("textured")] if self.state.material.texture in TEXTURE_KINDS else []
