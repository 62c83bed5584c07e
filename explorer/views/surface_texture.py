"""
The textured view's textures, by what a material declares it varies (``# texture: KIND`` in its file,
:attr:`explorer.materials.brd.Material.texture`) rather than by its name:

- ``thickness``: a thin film's OPD at normal incidence D_inc (:class:`explorer.views.thickness.ThicknessTexture`,
  Belcour & Barla 2017, Section 5);
- ``bragg``: a Bragg mirror's ``Lambda(x) = Lambda (0.5 + 0.5 T(x))`` and/or ``delta(x) = delta^T(x)``, ``T`` the
  grey texture in [0, 1] (:class:`BraggTexture`; Fourneau et al. 2024, supplemental Figure 7).

Both read the texture with the same planar parametrisation and bilinear filter (``shaders/views/textured.glsl``:
``surface_texture``), and hand the shader what it needs through :meth:`gl_arguments` and the numpy twin
through :meth:`model_options`.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from explorer.errors import LocatedError
from explorer.resources import DEFAULT_TEXTURE
from explorer.views.thickness import ThicknessTexture, load_grey

#: ``--mapping`` choices of a Bragg mirror's texture (:data:`explorer.physics.bragg.TEXTURE_MAPPINGS`).
MAPPINGS = ("both", "lambda", "delta", "none")
#: What ``# texture:`` may declare.
TEXTURE_KINDS = ("thickness", "bragg")


@dataclass
class BraggTexture:
    """``T``: float32 ``(H_t, W_t)`` grey values in [0, 1], rows from the top; ``mapping``: :data:`MAPPINGS`."""

    T: np.ndarray
    mapping: str = "both"
    source: str = "<array>"
    #: No prefiltering: Section 5's is the thin film's.
    prefilter = False

    def __post_init__(self):
        if self.mapping not in MAPPINGS:
            raise LocatedError("--mapping", None, f"{self.mapping!r} is not one of {', '.join(MAPPINGS)}")

    @classmethod
    def from_file(cls, path: str | Path = DEFAULT_TEXTURE, mapping: str = "both"):
        return cls(load_grey(path).astype(np.float32), mapping, str(path))

    @property
    def d_inc(self) -> np.ndarray:  # the texture's array, as ThicknessTexture names it (size checks)
        return self.T

    def per_pixel(self, x, y, width: int, height: int) -> tuple[np.ndarray, np.ndarray]:
        """``(T, 0)`` at the pixels ``p = (x, y)``: the same bilinear read as the film's (:meth:`ThicknessTexture.sample`)."""
        return ThicknessTexture(self.T).per_pixel(x, y, width, height)

    def at_uv(self, u, v) -> tuple[np.ndarray, np.ndarray]:
        return ThicknessTexture(self.T).at_uv(u, v)

    def model_options(self) -> dict:
        return {"mapping": self.mapping}

    def gl_arguments(self, material, values, width: int, height: int, draft: bool = False) -> dict:
        """
        ``inputs`` and ``uniforms`` of :meth:`explorer.gpu.Renderer.render`: the texture, the mapping, the tabulated
        method's table (``draft``: :func:`textured_draft_table`, the app's while a slider moves).
        """
        from explorer.materials.models import model_for
        from explorer.physics.bragg import TEXTURE_MAPPINGS

        model = model_for(material, values)
        table = np.zeros((1, 1, 3), np.float32)
        if model is not None and model.method.needs_table:
            if draft:
                table = textured_draft_table(model.mirror, self.mapping)
            else:
                table = np.asarray(model.texture_table(self.mapping), np.float32)
        inputs = {"surface_texture": self.T[..., None], "surface_moments": np.zeros((1, 1, 2), np.float32), "bragg_texture_table": table}
        return {"inputs": inputs, "uniforms": {"prefilter": False, "texture_mapping": int(TEXTURE_MAPPINGS[self.mapping])}}


@dataclass
class MapTexture:
    """
    Structure maps (``design --target-image``'s output, :mod:`explorer.views.maps`) on a material that declares them
    (:class:`explorer.materials.twins.StructureMaps`, its twin's ``Capabilities(maps=...)``): each texel its own
    structure, the mapped parameters from their maps, the others the material's values (``values``: the folder's fixed
    ones over the material's). Read as the textured view reads its texture (planar, ``shaders/views/textured.glsl``), but
    the nearest texel unfiltered: the surface value is the texel's index into the declaration's table
    (:func:`explorer.physics.structure_maps.structure_table`, lib/structure_maps.glsl). Off the maps' mask the surface
    is black.
    """

    #: The maps as read (name: float ``(H, W)``, NaN off the mask), for the Texture window.
    maps: dict
    #: The material's values the maps complete (the material's, the folder's fixed ones over them).
    values: dict
    #: What the material declares a texel holds (:class:`explorer.materials.twins.StructureMaps`).
    declaration: object
    source: str = "<maps>"
    prefilter = False

    def __post_init__(self):
        self.structures = self.declaration.table(self.values, self.maps)
        height, width = next(iter(self.maps.values())).shape
        self.index = np.arange(height * width, dtype=np.float32).reshape(height, width)

    @classmethod
    def from_folder(cls, folder, material, values) -> tuple["MapTexture", dict]:
        """The maps of ``folder`` on ``material`` and the values they complete (``values`` with the folder's fixed ones)."""
        from explorer.materials.twins import capabilities_of
        from explorer.views.maps import check_maps, read_maps

        try:
            params, maps = read_maps(folder)
        except ValueError as error:
            path, _, message = str(error).partition(": ")  # read_maps's lines begin with the file at fault
            raise LocatedError(path, None, message) from None
        fixed = check_maps(Path(folder), params, maps, material)
        values = {**values, **fixed}
        return cls(maps, values, capabilities_of(material).maps, str(folder)), values

    @property
    def d_inc(self) -> np.ndarray:  # the texture's array, as ThicknessTexture names it (size checks)
        return self.index

    def per_pixel(self, x, y, width: int, height: int) -> tuple[np.ndarray, np.ndarray]:
        """``(index, 0)`` of the nearest texel at the pixels ``p = (x, y)``: the shader's ``surface_value`` with ``surface_nearest``."""
        f32 = np.float32
        return self.at_uv(f32(0.5) * (x + f32(1.0)), f32(0.5) * (f32(1.0) - y))

    def at_uv(self, u, v) -> tuple[np.ndarray, np.ndarray]:
        """The nearest texel's index at texture coordinates ``(u, v)`` (float32, clamped), as ``surface_at``."""
        f32 = np.float32
        h, w = self.index.shape
        i = np.clip(np.floor(np.asarray(u, f32) * f32(w)).astype(np.int64), 0, w - 1)
        j = np.clip(np.floor(np.asarray(v, f32) * f32(h)).astype(np.int64), 0, h - 1)
        return self.index[j, i].astype(np.float64), np.zeros(np.shape(u))

    def model_options(self) -> dict:
        return {"mapping": "maps", "structures": self.structures}

    def gl_arguments(self, material, values, width: int, height: int, draft: bool = False) -> dict:
        """``inputs`` and ``uniforms`` of :meth:`explorer.gpu.Renderer.render`: the texel indices and the structure table."""
        from explorer.physics.structure_maps import MAPS_MAPPING

        inputs = {"surface_texture": self.index[..., None], "surface_moments": np.zeros((1, 1, 2), np.float32),
                  "bragg_texture_table": np.zeros((1, 1, 3), np.float32), "structure_maps": self.structures}
        return {"inputs": inputs, "uniforms": {"prefilter": False, "surface_nearest": True, "texture_mapping": MAPS_MAPPING}}


#: Rows in T of :func:`textured_draft_table` (the exact table refines to up to 129): ~0.1 s, mean |error| ~4e-2
#: against it on the default mirror (17 rows: 0.2 s, ~1e-2, but half as many drafts a second in the app).
TEXTURED_DRAFT_ROWS = 9


def textured_draft_table(mirror, mapping: str, rows: int | None = None) -> np.ndarray:
    """
    A quick stand-in for :func:`explorer.physics.bragg.textured_rgb_table` while a slider moves: ``rows`` rows
    (default :data:`TEXTURED_DRAFT_ROWS`) in
    ``T`` (uniform, so that the shader's bilinear lookup is unchanged) of the mirror's draft table
    (:func:`explorer.physics.bragg.draft_rgb_table`: ``DRAFT_SIZE`` columns, the draft converged rule) at
    ``textured_mirror(mirror, T, mapping)`` (Fourneau et al. 2024, supplemental Figure 7). ~12 ms a row; the exact
    table follows on release. Never a reference.
    """
    from explorer.physics import bragg

    rows = TEXTURED_DRAFT_ROWS if rows is None else rows
    if bragg.TEXTURE_MAPPINGS[mapping] == 0:
        rows = 2  # nothing varies with T: two equal rows, as in the exact table
    table = []
    for T in np.linspace(0.0, 1.0, rows):
        m = bragg.textured_mirror(mirror, T, mapping)  # 0-d Lambda and delta: the draft rule takes scalars
        table.append(bragg.draft_rgb_table(bragg.BraggMirror(m.n1, m.n2, float(m.Lambda), float(m.delta), m.N, m.nh)))
    table = np.ascontiguousarray(np.stack(table), dtype=np.float32)
    table.setflags(write=False)
    return table


def textured_builtins() -> str:
    """The built-in materials that declare a ``# texture:`` (for messages), comma-separated."""
    from explorer.materials.brd import load_material
    from explorer.resources import builtin_materials

    return ", ".join(name for name, path in builtin_materials().items() if load_material(path).texture is not None)


def check_texture_kind(material) -> str:
    """The material's declared texture kind, or a one-line :class:`LocatedError` saying which materials have a textured view."""
    from explorer.materials.brd import MaterialError

    kind = getattr(material, "texture", None)
    if kind is None:
        raise MaterialError(material.path, None, "the textured view needs a material that declares '# texture: "
                            f"{'|'.join(TEXTURE_KINDS)}' ({textured_builtins()})")
    if kind not in TEXTURE_KINDS:
        raise MaterialError(material.path, None, f"'# texture: {kind}' is not one of {', '.join(TEXTURE_KINDS)}")
    return kind


def default_texture(material):
    """The textured view's default texture for ``material`` (the shipped noise, over the default D_inc range for a film)."""
    return BraggTexture.from_file() if check_texture_kind(material) == "bragg" else ThicknessTexture.from_file()
