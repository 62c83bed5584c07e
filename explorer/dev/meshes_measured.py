"""
The measurements of docs/meshes.md: meshes in the lit view, MERL tables, and the env view's environment
sampling, printed as Markdown (``python -m explorer.dev.meshes_measured``; a few minutes on llvmpipe).

Measured, not asserted: frame times (glFinish-bounded, median of 5) at 512², the GL-vs-numpy pixels that
differ, and the env view's standard error with and without environment sampling at equal samples.
"""

from __future__ import annotations

import tempfile
import time
from pathlib import Path

import numpy as np

from explorer.gpu import Renderer
from explorer.gpu.env import ProgressiveEnvRender
from explorer.gpu.mesh import MESH_TEMPLATES, mesh_normals, render_mesh
from explorer.materials.brd import load_material
from explorer.materials.methods import BraggMethod
from explorer.materials.merl import tabulate, write_merl
from explorer.materials.models import BraggMirrorModel, GGXSchlickModel, model_for
from explorer.materials.twins import shipped_file
from explorer.views.env import ENVIRONMENTS
from explorer.views.geometry import brdf_view_geometry
from explorer.views.mesh import SHAPES, rasterise
from explorer.views.render import render_numpy

SIZE = 512
REPEATS = 5


def _median_ms(function) -> float:
    times = []
    for _ in range(REPEATS):
        start = time.perf_counter()
        function()
        times.append((time.perf_counter() - start) * 1e3)
    return float(np.median(times))


def mesh_rows(renderer: Renderer) -> list[str]:
    material = load_material(shipped_file(BraggMirrorModel))
    values = material.resolve({"method": int(BraggMethod.TABULATED)})
    lines = ["| model | triangles | normals pass (ms) | lit frame (ms) | numpy rasteriser (s) | GL vs numpy: pixels compared, max rel. error |",
             "|---|---|---|---|---|---|"]
    sphere = renderer.time_frame(material, values, "lit", SIZE, SIZE)
    lines.append(f"| sphere | - | - | {sphere:.1f} | - | - |")
    for name, make in SHAPES.items():
        mesh = make()
        normals = _median_ms(lambda: mesh_normals(renderer, mesh, SIZE, SIZE))
        surface = mesh_normals(renderer, mesh, SIZE, SIZE)
        frame = float(np.median([renderer.time_frame(material, values, MESH_TEMPLATES["lit"], SIZE, SIZE,
                                                     inputs={"mesh_normals": surface}) for _ in range(REPEATS)]))
        start = time.perf_counter()
        raster = rasterise(mesh, 256, 256)
        seconds = time.perf_counter() - start
        gl = render_mesh(renderer, material, values, "lit", mesh, 256, 256).astype(np.float64)
        reference = render_numpy(model_for(material, values), "lit", 256, 256, mesh=mesh).astype(np.float64)
        safe = raster.covered & (raster.margin > 1e-3) & (raster.depth_gap > 1e-3)
        error = np.abs(gl - reference).max(axis=-1)[safe] / np.maximum(np.abs(reference).max(axis=-1)[safe], 1e-3)
        lines.append(f"| {name} | {len(mesh.triangles)} | {normals:.1f} | {frame:.1f} | {seconds:.2f} (256²) | "
                     f"{int(safe.sum())} of {int(raster.covered.sum())}, {error.max():.1e} |")
    return lines


def merl_rows(renderer: Renderer) -> list[str]:
    def analytic(L, V):
        H = (L + V) / np.linalg.norm(L + V, axis=-1, keepdims=True)
        return 0.1 / np.pi + np.exp(-8.0 * (1.0 - H[..., 2]))[..., None] * np.array([0.9, 0.6, 0.3])

    with tempfile.TemporaryDirectory() as directory:
        path = write_merl(Path(directory) / "analytic.binary", tabulate(analytic))
        start = time.perf_counter()
        material = load_material(path)
        load_s = time.perf_counter() - start
        lines = ["| view | frame at 512² (ms) | pixels at 256² where GL reads a neighbouring bin |", "|---|---|---|"]
        renderer.render(material, {}, "lit", 8, 8)  # the table's upload, once
        model = model_for(material, {})
        for view, light in (("lit", (30.0, 120.0)), ("slice", None), ("scatter", (50.0, 200.0))):
            frame = float(np.median([renderer.time_frame(material, {}, view, SIZE, SIZE, light=light) for _ in range(REPEATS)]))
            gl = renderer.render(material, {}, view, 256, 256, light=light).astype(np.float64)
            reference = render_numpy(model, view, 256, 256, light=light).astype(np.float64)
            off = np.abs(gl - reference).max(axis=-1) > 2e-3 * np.maximum(np.abs(reference).max(axis=-1), 1e-3)
            lines.append(f"| {view} | {frame:.1f} | {int(off.sum())} of {off.size} |")
    return [f"Loading a 35 MB MERL file: {load_s:.2f} s.", ""] + lines


def env_rows(renderer: Renderer) -> list[str]:
    lines = ["| environment | material | median SE ratio (with / without) | first pass at 512², 1 spp (ms) |", "|---|---|---|---|"]
    size, spp = 32, 512
    inside = brdf_view_geometry("lit", size, size)[5]
    for env_name in ("sky", "studio"):
        environment = ENVIRONMENTS[env_name]()
        for path, overrides in ((GGXSchlickModel, {"alpha": 0.6, "F0": 0.9}), (GGXSchlickModel, {"alpha": 0.1, "F0": 0.9})):
            material = load_material(shipped_file(path))
            values = material.resolve(overrides)
            errors = []
            for weight in (0.5, 0.0):
                render = ProgressiveEnvRender(renderer, material, values, environment, size, size, environment_sampling=weight)
                render.step(spp)
                errors.append(render.standard_error()[inside].astype(np.float64))
                render.release()
            ratio = float(np.median(errors[0] / np.maximum(errors[1], 1e-30)))
            render = ProgressiveEnvRender(renderer, material, values, environment, SIZE, SIZE)
            first = render._pass(render._bindings(), 1)
            render.release()
            lines.append(f"| {env_name} | ggx alpha {overrides['alpha']} | {ratio:.2f} | {first:.1f} |")
    return lines


def main() -> None:
    renderer = Renderer()
    print(f"### Meshes (lit view, {BraggMirrorModel.name} tabulated)\n")
    print("\n".join(mesh_rows(renderer)))
    print("\n### MERL tables (an analytic BRDF written as a MERL file)\n")
    print("\n".join(merl_rows(renderer)))
    print("\n### Environment sampling (env view, 512 spp at 32², standard error per pixel and channel)\n")
    print("\n".join(env_rows(renderer)))


if __name__ == "__main__":
    main()
