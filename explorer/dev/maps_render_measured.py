"""
``python -m explorer.dev.maps_render_measured [--size N] [--maps N]``: structure maps on the sphere and on meshes, GL
against the numpy twin, and their times. Smooth random maps (Lambda 150-320 nm, delta 0.3-0.7, N 6-30, as the painting
round trip draws them) on the paper's indices; prints per view and method the largest |GL - numpy| and the worst
pixel's share of its tolerance (explorer.views.twin_check), and the seconds of each engine. The numbers of
docs/textured_bragg.md's structure maps.
"""

from __future__ import annotations

import argparse
import json
import tempfile
import time
from pathlib import Path

import numpy as np


def random_maps(size: int, seed: int = 7) -> dict[str, np.ndarray]:
    """Smooth random fields (a few low Fourier modes) within the painting round trip's box."""
    rng = np.random.default_rng(seed)
    y, x = np.mgrid[0:size, 0:size] / size

    def field():
        f = sum(rng.normal() * np.cos(2 * np.pi * (kx * x + ky * y) + rng.uniform(0, 2 * np.pi)) for kx in range(3) for ky in range(3))
        return (f - f.min()) / (f.max() - f.min())

    return {"Lambda": 150.0 + 170.0 * field(), "delta": 0.3 + 0.4 * field(), "N": np.rint(6.0 + 24.0 * field())}


def write_folder(folder: Path, maps: dict[str, np.ndarray]) -> None:
    from explorer.materials.models import BraggMirrorModel
    from explorer.views.images import write_image

    folder.mkdir(parents=True, exist_ok=True)
    for name, image in maps.items():
        write_image(np.repeat(image[..., None], 3, axis=-1).astype(np.float32), folder / f"{name}.exr")
    params = {"material": BraggMirrorModel.name, "model": BraggMirrorModel.name, "fixed": {"n1": 1.0, "n2": 1.5, "nh": 0.0}, "free": list(maps),
              "angles_deg": [0.0], "seed": 7, "shape": list(next(iter(maps.values())).shape)}
    (folder / "params.json").write_text(json.dumps(params), encoding="utf-8")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.strip().splitlines()[0])
    parser.add_argument("--size", type=int, default=96, help="image side in pixels (default 96)")
    parser.add_argument("--maps", type=int, default=64, help="map side in texels (default 64)")
    args = parser.parse_args()

    from explorer.gpu import Renderer
    from explorer.gpu.env import render_env
    from explorer.materials.brd import load_material
    from explorer.materials.methods import BraggMethod
    from explorer.materials.models import BraggMirrorModel, model_for
    from explorer.resources import material_path
    from explorer.views.env import EnvironmentMap, env_integral_numpy
    from explorer.views.mesh import rasterise, torus
    from explorer.views.surface_texture import MapTexture
    from explorer.views.twin_check import Twins, compare, compared_pixels
    from explorer.rendering import render_material

    mirror = load_material(material_path(BraggMirrorModel.name))
    renderer = Renderer()
    environment = EnvironmentMap.default()
    size = args.size
    with tempfile.TemporaryDirectory() as temporary:
        folder = Path(temporary) / "maps"
        write_folder(folder, random_maps(args.maps))
        print(f"{args.maps}x{args.maps} random maps, {size}x{size} images")
        for method in (int(BraggMethod.TABULATED), int(BraggMethod.REFERENCE)):
            texture, values = MapTexture.from_folder(folder, mirror, mirror.resolve({"method": method}))
            for what, mesh in (("sphere", None), ("torus", torus())):
                times = {}
                for engine in ("gl", "gl", "numpy"):  # GL twice: the first compiles the program
                    start = time.perf_counter()
                    image = render_material(mirror, values, "textured", size, size, engine, (20.0, 30.0), texture, mesh=mesh,
                                            renderer=renderer)
                    times[engine if engine not in times else "gl warm"] = (time.perf_counter() - start, image)
                if mesh is None:
                    compared = compared_pixels("textured", size, size)
                else:
                    surface = rasterise(mesh, size, size)
                    scaled = surface.uvs * args.maps
                    compared = surface.covered & (surface.margin > 1e-3) & (surface.depth_gap > 1e-3) & \
                        (np.abs(scaled - np.rint(scaled)).min(axis=-1) > 1e-3)
                result = compare(Twins(times["gl"][1], times["numpy"][1], compared, "textured", (20.0, 30.0)))
                print(f"textured {what:6s} method {method}: max |GL - numpy| {result.max_difference:.2e}, worst {result.worst_ratio:.3f} "
                      f"of tolerance, {_over(times['gl'][1], times['numpy'][1], compared)}; gl {times['gl'][0]:.2f} s (warm "
                      f"{times['gl warm'][0]:.2f} s), numpy {times['numpy'][0]:.2f} s")
            start = time.perf_counter()
            small = size // 2
            gl = render_env(mirror, values, small, small, environment=environment, spp=1, renderer=renderer, surface=texture)
            gl_time = time.perf_counter() - start
            start = time.perf_counter()
            reference = env_integral_numpy(model_for(mirror, values), environment, small, small, surface=texture)
            result = compare(Twins.of(gl, reference, "env"))
            print(f"env      sphere method {method} ({small}x{small}): max |GL - numpy| {result.max_difference:.2e}, worst "
                  f"{result.worst_ratio:.3f} of tolerance, {_over(gl, reference, compared_pixels('env', small, small))}; "
                  f"gl {gl_time:.2f} s, numpy {time.perf_counter() - start:.2f} s")


def _over(gl: np.ndarray, reference: np.ndarray, compared: np.ndarray, threshold: float = 1e-4) -> str:
    """How many compared pixels differ by more than ``threshold`` (a box choice flipped between float32 and float64)."""
    difference = np.abs(gl.astype(np.float64) - reference).max(axis=-1)[compared]
    return f"{int((difference > threshold).sum())} of {int(compared.sum())} pixels over {threshold:g}"


if __name__ == "__main__":
    main()
