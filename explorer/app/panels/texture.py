"""
The Texture window: the textured view (:mod:`explorer.views.surface_texture`) of a material that declares
``# texture:``: a thin film's D_inc over a range, or a Bragg mirror's Lambda and/or delta (supplemental
Figure 7), from a grey image (the shipped noise by default), lit by the app's light; or structure maps (a folder
``design --target-image`` wrote, :class:`explorer.views.surface_texture.MapTexture`), each map shown below. On the
sphere or a mesh (by its texture coordinates), lit or under the environment, as ``render --mesh --view textured|env``.
"""

from __future__ import annotations

import functools

import numpy as np

from explorer.rendering import request_view
from explorer.app.camera import light_vector
from explorer.app.panels.base import Panel, combo, record, show_image
from explorer.app.scheduler import model_mesh
from explorer.app.state import SPHERE_MODELS
from explorer.errors import LocatedError
from explorer.materials.twins import capabilities_of
from explorer.resources import DEFAULT_TEXTURE
from explorer.views.surface_texture import MAPPINGS, TEXTURE_KINDS, BraggTexture, MapTexture, textured_builtins
from explorer.views.thickness import DEFAULT_DINC_RANGE, DINC_MAX, ThicknessTexture

#: Samples per pixel the window's env render stops at (a smooth mirror's Dirac is exact after one).
ENV_SAMPLES = 256


@functools.cache
def _textured_builtins() -> str:
    """:func:`textured_builtins`, read once (it loads every built-in material)."""
    return textured_builtins()


def no_texture_text(name: str) -> str:
    """What the Texture tab says for a material whose surface no image can vary (in words, not the file's syntax)."""
    return (f"{name} looks the same all over its surface: nothing in it follows an image. This tab shows a material "
            "whose look varies across the surface with a grey image: a thin film whose thickness follows it, or a smooth "
            f"Bragg mirror whose period and layer ratio follow it: File > Open... one ({_textured_builtins()} do).")


class TexturePanel(Panel):
    title = "Texture"
    dock = "right_top"
    gl_order = 7
    #: GL time (ms) a frame gives the view while a slider moves (the sphere's: DRAG_BUDGET_MS): a preview that fits.
    drag_budget_ms = 6.0

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
        self._pending = None  # (key, values, draft, future) of the arguments being built on the worker thread
        self._draft = False  # the arguments hold the draft table (textured_draft_table), not the exact one
        self._executor = None
        #: Under the environment: the env view's progressive Monte Carlo with the surface texture.
        self.environment = False
        self._env = None  # (key, ProgressiveEnvRender, AccumulatedImage)
        self._env_reported = None  # the env render last reported
        #: A map folder (open --maps, or typed here): its maps on the mirror instead of the grey image.
        self.maps_path = app.state.maps_folder
        self._map_textures: dict = {}  # map name -> texture of its image, for the current folder
        #: The sphere or a mesh of SPHERE_MODELS (render --mesh), the texture carried by its coordinates.
        self.model = "sphere"
        self._mesh_inputs = None  # (model, size, {"mesh_normals", "mesh_uvs"}) of the mesh shown
        #: The mean RGB of each image shown, by "textured:MODEL" or "env:MODEL", for the current values (reported).
        self._shown: dict = {}

    def _texture(self, kind: str, mappable: bool):
        """The surface texture of the current settings (loaded again only when they change)."""
        maps = self.maps_path.strip() if mappable else ""
        key = (kind, self.path, self.mapping, tuple(self.dinc_range), maps)
        if key != self._surface_key:
            self._surface_key = key
            try:
                if maps:
                    self._surface, values = MapTexture.from_folder(maps, self.state.material, self.state.values)
                    self.state.values = self.state.material.resolve(values)  # the folder's fixed values
                    self.state.maps_folder = maps
                    self._map_images(self._surface)
                elif kind == "bragg":
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
            text = no_texture_text(state.material_path.name)
            imgui.text_wrapped(text)
            state.texture_view = {"message": text}
            return
        mappable = capabilities_of(state.material).maps is not None
        if mappable:
            _, self.maps_path = imgui.input_text("map folder (design --out-maps)", self.maps_path)
            record(state, "maps_folder")
        maps = mappable and bool(self.maps_path.strip())
        if not maps:
            _, self.path = imgui.input_text("texture (grey image)", self.path)
        if maps:
            imgui.text_wrapped("each texel its own structure: the maps below, the other values the folder's")
        elif kind == "bragg":
            self.mapping = combo(state, "mapping", self.mapping, [(n, n) for n in MAPPINGS], self.mapping, "mapping",
                                 "mapping_combo") or self.mapping
            imgui.text_wrapped("Lambda (0.5 + 0.5 T), delta^T (supplemental Fig. 7)")
        else:
            _, self.dinc_range = imgui.slider_float2("D_inc range (nm)", self.dinc_range, 0.0, DINC_MAX, "%.0f")
            self.dinc_range = list(self.dinc_range)
        _, self.environment = imgui.checkbox("under the environment (env view)", self.environment)
        record(state, "texture_env")
        imgui.set_next_item_width(110)
        self.model = combo(state, "model##texture", self.model, [(n, n) for n in SPHERE_MODELS], self.model, "texture_model",
                           "texture_model_combo") or self.model
        surface = self._texture(kind, mappable)
        if self.message:
            imgui.text_colored(imgui.ImVec4(1.0, 0.35, 0.3, 1.0), self.message)
        if surface is None:
            return
        size = (state.view_size, state.view_size)  # the sphere's resolution (View size), as bench --app times it
        job = self.scheduler.job("textured")
        dragging = self.app.dragging
        values = self.scheduler.prefetcher.values(state.material, state.values, dragging)
        key = (id(state.material), tuple(sorted((k, str(v)) for k, v in values.items())), self._surface_key)
        if self._pending is not None and self._pending[3].done():
            pending_key, pending_values, draft, future = self._pending
            self._pending = None
            try:
                self._arguments, self._arguments_key, self._values, self._draft = future.result(), pending_key, pending_values, draft
            except Exception as error:  # noqa: BLE001 - a material's own error, shown in the window
                self.message = f"{type(error).__name__}: {error}"
        # The tabulated method's (cos theta, T) table takes seconds: while a slider moves the worker thread builds
        # drafts (textured_draft_table, ~0.2 s) of the newest values, the last image shown meanwhile; on release,
        # the exact table. One build at a time: the newest values go next.
        draft = dragging and _needs_table(state.material, values)
        shown = self._arguments_key == key and not (self._draft and not dragging)
        if not shown and self._pending is None:
            import concurrent.futures

            if self._executor is None:
                self._executor = concurrent.futures.ThreadPoolExecutor(max_workers=1, thread_name_prefix="texture")
            future = self._executor.submit(surface.gl_arguments, state.material, dict(values), *size, draft=draft)
            self._pending = (key, dict(values), draft, future)
        if self._draft:  # for a frame's record (bench --app)
            self.scheduler.drafts.add("textured")
        else:
            self.scheduler.drafts.discard("textured")
        if self._arguments is None:
            imgui.text("building the texture's tables…")
            return
        if isinstance(surface, MapTexture):
            self._draw_maps(imgui, surface)
        if self.environment:
            source = self._env_source(surface, size)
            show_image(state, self.scheduler.show("textured_env", size, source), size, "textured_image")
            done = source.render.samples >= self._env_samples
            imgui.text(f"env: {source.render.samples} samples per pixel ({'done' if done else 'refining'})")
            if not done:
                state.texture_view = {"running": True, "draft": self._draft}
            elif self._env_reported is not self._env:
                self._env_reported = self._env
                self._report(kind, surface, size, f"env:{self.model}", source.render.image())
            return
        mesh = self._mesh()
        if mesh is not None:  # its rasterised normals and texture coordinates (explorer.gpu.mesh), once per model and size
            from explorer.gpu.mesh import MESH_TEMPLATES

            request_view(job, state.material, self._values, MESH_TEMPLATES["textured"], size, light=light_vector(state.light, state.camera),
                         surface=self._arguments, inputs=self._mesh_surface(mesh, size), inputs_key=(self.model, size, self._arguments_key),
                         dragging=self.app.dragging)
        else:
            request_view(job, state.material, self._values, "textured", size, light=light_vector(state.light, state.camera),
                         surface=self._arguments, dragging=self.app.dragging)
        show_image(state, self.scheduler.show("textured", size, job), size, "textured_image")
        imgui.text(("done" if job.complete else f"refining {100 * job.progress:.0f}%") + ("  (draft table)" if self._draft else "")
                   + (f"  {job.error}" if job.error else ""))
        if not (job.complete and self._arguments_key == key and not self._draft):  # a new image on its way (scripts wait_for it)
            state.texture_view = {"running": True, "draft": self._draft}
        elif job.generation != self._generation or not state.texture_view or state.texture_view.get("running"):
            self._generation = job.generation
            self._report(kind, surface, size, f"textured:{self.model}", job.read())

    def _report(self, kind: str, surface, size, shown: str, image) -> None:
        """``state.texture_view``: the settings, the values and the image's mean RGB (and every image's shown at these values)."""
        state = self.state
        mean = np.asarray(image, np.float64).reshape(-1, 3).mean(axis=0).tolist()
        values = {k: (list(v) if isinstance(v, tuple) else v) for k, v in self._values.items()}
        if self._shown.get("values") != values:
            self._shown = {"values": values, "means": {}}
        self._shown["means"][shown] = mean
        state.texture_view = {"kind": kind, "path": self.path, "mapping": self.mapping, "dinc_range": list(self.dinc_range),
                              "values": values, "light": list(light_vector(state.light, state.camera)), "size": list(size),
                              "draft": False, "model": self.model, "environment": state.environment if self.environment else None,
                              "mean_rgb": mean, "shown": dict(self._shown["means"])}
        if isinstance(surface, MapTexture):
            state.texture_view["maps_folder"] = self.maps_path.strip()
            state.texture_view["maps"] = {name: shown for name, (_, shown) in self._map_textures.items()}

    def _mesh(self):
        """The mesh chosen (None: the sphere)."""
        return model_mesh(self.model, self.scheduler.env.meshes)

    def _mesh_surface(self, mesh, size) -> dict:
        """The mesh's normals and texture coordinates at ``size`` (:func:`explorer.gpu.mesh.mesh_surface`), once per model and size."""
        if self._mesh_inputs is None or self._mesh_inputs[:2] != (self.model, size):
            from explorer.gpu.mesh import mesh_surface

            normals, uvs = mesh_surface(self.scheduler.renderer, mesh, *size)
            self._mesh_inputs = (self.model, size, {"mesh_normals": normals, "mesh_uvs": uvs})
        return self._mesh_inputs[2]

    def _map_images(self, surface: MapTexture) -> None:
        """Each map as a grey image (its finite range black to white, off the mask dark red), uploaded once per folder."""
        for texture, _ in self._map_textures.values():
            self.app.renderer.resources.release(texture)
        self._map_textures = {}
        for name, image in surface.maps.items():
            finite = np.isfinite(image)
            low, high = (float(image[finite].min()), float(image[finite].max())) if finite.any() else (0.0, 0.0)
            grey = np.where(finite, (image - low) / (high - low) if high > low else 0.5, 0.0)
            rgb = np.stack([np.where(finite, grey, 0.5), grey, grey], axis=-1).astype(np.float32)
            texture = self.app.renderer.resources.texture(rgb, origin=f"map {name}")
            self._map_textures[name] = (texture, {"min": low, "max": high, "size": [image.shape[1], image.shape[0]],
                                                  "mean_grey": float(grey[finite].mean()) if finite.any() else 0.0})

    def _draw_maps(self, imgui, surface: MapTexture) -> None:
        """The maps side by side (rows from the top, nearest texels), each with its range."""
        if not self._map_textures:
            return
        count = len(self._map_textures)
        side = max(32.0, (imgui.get_content_region_avail().x - 8.0 * count) / count)
        for k, (name, (texture, shown)) in enumerate(self._map_textures.items()):
            if k:
                imgui.same_line()
            imgui.begin_group()
            w, h = shown["size"]
            imgui.image(imgui.ImTextureRef(texture.glo), imgui.ImVec2(side, side * h / w), imgui.ImVec2(0, 0), imgui.ImVec2(1, 1))
            record(self.state, f"map:{name}")
            imgui.text(f"{name} {shown['min']:.4g}..{shown['max']:.4g}")
            imgui.end_group()

    def _env_source(self, surface, size):
        """The env render of the current arguments' values under ``surface`` (a new one when they change)."""
        from explorer.gpu.display import AccumulatedImage
        from explorer.gpu.env import ProgressiveEnvRender

        key = (self._arguments_key, self.model, self.state.environment, self.state.env_rotation)
        if self._env is None or self._env[0] != key:
            if self._env is not None:
                self._env[1].release()
            # The env mode's environment and probe rotation (its loaded maps: EnvScheduler.environment).
            environment = self.scheduler.env.environment(self.state.environment).rotated(self.state.env_rotation)
            # The tables are those the worker built for these values (cached): no wait here.
            render = ProgressiveEnvRender(self.scheduler.renderer, self.state.material, self._values, environment, *size,
                                          surface=surface, mesh=self._mesh())
            from explorer.materials.models import model_for

            model = model_for(self.state.material, self._values)
            self._env_samples = 1 if getattr(model, "mirror_only", False) else ENV_SAMPLES
            self._env = (key, render, AccumulatedImage(render))
        return self._env[2]

    def gl_jobs(self) -> list:
        if self.state.material.texture not in TEXTURE_KINDS:
            return []
        if self.environment and self._env is not None:
            return [] if self._env[1].samples >= self._env_samples else [_EnvWork(self._env[1])]
        return [self.scheduler.job("textured")]


def _needs_table(material, values) -> bool:
    """Whether ``material`` at ``values`` draws the textured view from a table (the tabulated method's; drafts while dragging)."""
    from explorer.materials.models import model_for

    model = model_for(material, values)
    return bool(model is not None and getattr(getattr(model, "method", None), "needs_table", False))


class _EnvWork:
    """A progressive env render as one of the frame's GL jobs (``work(budget_ms)``)."""

    def __init__(self, render):
        self.render = render

    def work(self, budget_ms: float) -> float:
        self.render.advance(max(0.5 * budget_ms, 5.0))
        return budget_ms
