"""
The colours of structure maps (:mod:`explorer.design.paint`'s output): each texel's structure, the fixed values
and the map's free parameters, seen at one angle. The flat textured view of a painted material: what a target image
of ``design --target-image`` shows, so that a map folder renders back to the image it was designed from.
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Mapping, Sequence

import numpy as np

from explorer.design.paint import PaintResult


def map_structures(fixed: Mapping[str, float], maps: Mapping[str, np.ndarray]) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """The texels that hold a structure (every map finite) and their design values (flat arrays, in texel order)."""
    shape = next(iter(maps.values())).shape
    inside = np.logical_and.reduce([np.isfinite(m) for m in maps.values()])
    values = {name: np.full(int(inside.sum()), float(v)) for name, v in fixed.items()}
    values.update({name: np.asarray(m, dtype=np.float64)[inside] for name, m in maps.items()})
    return inside.reshape(shape), values


def map_colours(model_name: str, fixed: Mapping[str, float], maps: Mapping[str, np.ndarray], theta_deg: float) -> np.ndarray:
    """
    ``(H, W, 3)`` linear RGB: each texel's converged spectral colour at ``theta_deg`` (the design's forward model,
    :attr:`explorer.design.base.DesignModel.converged` with ``final``: the reference); black where a map is NaN.
    """
    from explorer.design import design_model

    model = design_model(model_name)
    inside, values = map_structures(fixed, maps)
    cos_theta = np.array([np.cos(np.radians(theta_deg))])
    out = np.zeros(inside.shape + (3,))
    names = sorted(values)
    if int(inside.sum()):
        # Painted regions repeat one structure: each distinct one once, all of them in one call.
        table = np.stack([np.asarray(values[name], dtype=np.float64) for name in names], axis=1)
        distinct, index = np.unique(table, axis=0, return_inverse=True)
        colours = model.converged_rows({name: distinct[:, k] for k, name in enumerate(names)}, cos_theta)[:, 0]
        out[inside] = colours[np.ravel(index)]
    return out.astype(np.float32)


def flat_numpy(model, texture, theta_deg: float) -> np.ndarray:
    """
    The flat textured view by the numpy twin: one pixel a texel of ``texture`` (a surface texture of
    :mod:`explorer.views.surface_texture`), its colour at ``theta_deg`` by the material's method (the twin's
    ``surface_reflectance``). The twin of ``shaders/views/flat/textured.glsl`` (:func:`flat_gl`).
    """
    value = np.asarray(texture.d_inc, np.float64)
    cos_theta = np.full(value.shape, float(np.float32(np.cos(np.radians(theta_deg)))))  # the shader's float32 uniform
    return np.asarray(model.surface_reflectance(cos_theta, value, **texture.model_options()), np.float32)


def flat_gl(renderer, material, values, texture, theta_deg: float) -> np.ndarray:
    """The flat textured view on the GPU (``shaders/views/flat/textured.glsl``): :func:`flat_numpy`'s image."""
    height, width = texture.d_inc.shape
    arguments = texture.gl_arguments(material, values, width, height)
    uniforms = {**arguments["uniforms"], "flat_cos_theta": float(np.float32(np.cos(np.radians(theta_deg))))}
    return renderer.render(material, values, "flat/textured", width, height, inputs=arguments["inputs"], uniforms=uniforms)


# --------------------------------------------------------------------------------------------------
# Map folders and target images


def write_maps(result: PaintResult, out: Path, material: str, model_name: str, angles: Sequence[float], seed: int) -> list[Path]:
    """
    The maps as EXR (one per free parameter, the value in every channel; NaN off the mask), ``params.json``
    (the fixed values, the free ones, the angles), a CIEDE2000 EXR per angle, ``unreachable.png`` (white where no
    structure reaches) and ``report.json``. Every file written atomically.
    """
    from PIL import Image

    from explorer.files import atomic_output, write_text_atomic
    from explorer.views.images import write_image

    out.mkdir(parents=True, exist_ok=True)
    written = []
    for name, image in result.maps.items():
        path = out / f"{name}.exr"
        write_image(np.repeat(image[..., None], 3, axis=-1).astype(np.float32), path)
        written.append(path)
    params = {"material": material, "model": model_name, "fixed": result.fixed, "free": list(result.maps),
              "angles_deg": list(angles), "seed": seed, "shape": list(result.unreachable.shape)}
    write_text_atomic(out / "params.json", json.dumps(params, indent=2) + "\n")
    written.append(out / "params.json")
    for a, theta in enumerate(angles):
        path = out / f"delta_e_{theta:g}.exr"
        write_image(np.repeat(result.delta_e[a][..., None], 3, axis=-1).astype(np.float32), path)
        written.append(path)
    path = out / "unreachable.png"
    with atomic_output(path) as temporary:
        Image.fromarray(np.where(result.unreachable, 255, 0).astype(np.uint8), mode="L").save(temporary, format="PNG")
    written.append(path)
    write_text_atomic(out / "report.json", json.dumps(result.report(angles), indent=2) + "\n")
    written.append(out / "report.json")
    return written


def read_maps(folder: str | os.PathLike[str]) -> tuple[dict, dict[str, np.ndarray]]:
    """``params.json`` and the maps of a folder :func:`write_maps` wrote; ``ValueError`` (one line) otherwise."""
    folder = Path(folder)
    try:
        params = json.loads((folder / "params.json").read_text(encoding="utf-8"))
        names = list(params["free"])
    except (OSError, ValueError, KeyError, TypeError) as error:
        raise ValueError(f"{folder / 'params.json'}: not a map folder's parameters ({' '.join(str(error).split())[:100]})") from None
    maps = {name: _read_exr_channel(folder / f"{name}.exr") for name in names}
    if not maps:
        raise ValueError(f"{folder / 'params.json'}: no free parameter, so no map to read")
    first = names[0]
    for name, m in maps.items():
        if m.shape != maps[first].shape:
            (h, w), (h0, w0) = m.shape, maps[first].shape
            raise ValueError(f"{folder / (name + '.exr')}: {w}x{h} texels, but {first}.exr has {w0}x{h0}: the maps differ in size")
    return params, maps


def maps_material(folder: str | os.PathLike[str]) -> str:
    """The material a map folder's ``params.json`` names (for a command given no MATERIAL); ``LocatedError`` otherwise."""
    from explorer.errors import LocatedError

    path = Path(folder) / "params.json"
    try:
        name = json.loads(path.read_text(encoding="utf-8"))["material"]
    except (OSError, ValueError, KeyError, TypeError) as error:
        raise LocatedError(path, None, f"not a map folder's parameters ({' '.join(str(error).split())[:100]})") from None
    if not isinstance(name, str) or not name:
        raise LocatedError(path, None, "names no material: give MATERIAL")
    return name


def check_maps(folder: Path, params: Mapping, maps: Mapping[str, np.ndarray], material) -> dict[str, float]:
    """
    The folder's fixed values, once its maps fit ``material`` (the structure its twin declares it maps,
    :class:`explorer.materials.twins.StructureMaps`: each map a field of it, within its range); a one-line
    :class:`explorer.errors.LocatedError` naming the file otherwise.
    """
    from explorer.errors import LocatedError
    from explorer.materials.twins import capabilities_of

    declared = {p.name: p for p in material.parameters}
    if params.get("model") != material.model:
        raise LocatedError(folder / "params.json", None, f"maps of a {params.get('model')}, not of {material.model} ({Path(material.path).name})")
    declaration = capabilities_of(material).maps
    if declaration is None:
        raise LocatedError(folder / "params.json", None, f"maps are drawn on a structure a material's twin declares; "
                                                         f"{Path(material.path).name} declares none")
    fields = declaration.fields
    fixed = params.get("fixed") or {}
    if not isinstance(fixed, Mapping):
        raise LocatedError(folder / "params.json", None, "'fixed' is not an object of NAME: VALUE")
    for name, value in fixed.items():
        if name not in declared or not isinstance(value, (int, float)) or not np.isfinite(value):
            raise LocatedError(folder / "params.json", None, f"fixed {name} = {value!r}: not a number of a parameter of {Path(material.path).name}")
    for name, image in maps.items():
        path = folder / f"{name}.exr"
        if name not in declared or name not in fields:
            raise LocatedError(path, None, f"a map of {name}, which is not a structure parameter of {Path(material.path).name} "
                                           f"({', '.join(n for n in fields if n in declared)})")
        parameter = declared[name]
        finite = np.isfinite(image)
        outside = finite & ((image < parameter.min) | (image > parameter.max))
        if outside.any():
            j, i = np.argwhere(outside)[0]
            raise LocatedError(path, None, f"texel ({i}, {j}) = {image[j, i]:g}, outside {name}'s range {parameter.min:g}..{parameter.max:g}")
        if np.isinf(image).any():
            j, i = np.argwhere(np.isinf(image))[0]
            raise LocatedError(path, None, f"texel ({i}, {j}) is infinite (NaN marks a texel off the mask)")
    return {name: float(value) for name, value in fixed.items()}


def _read_exr_channel(path: Path) -> np.ndarray:
    """The first channel of a map's EXR (NaN kept: off the mask), ``ValueError`` (one line) when unreadable."""
    from explorer.views.env import _cv2

    cv2 = _cv2()
    pixels = cv2.imread(os.fspath(path), cv2.IMREAD_UNCHANGED) if path.is_file() else None
    if pixels is None:
        raise ValueError(f"{path}: no map there (or not an EXR OpenCV can read)")
    pixels = np.asarray(pixels, dtype=np.float64)
    return pixels if pixels.ndim == 2 else pixels[..., -1]  # BGR: the last is red, all equal


def read_target_image(path: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """
    A target image as the strips are read (:func:`explorer.views.images.read_linear_image`: 8/16-bit PNG and the
    like in sRGB, ``.exr``/``.npy`` linear): linear RGB ``(H, W, 3)``, clipped codes ``(H, W, 3)`` (bounds) and
    the alpha mask ``(H, W)`` (alpha above half; all true without alpha). ``ValueError`` (one line) otherwise.
    """
    from explorer.views.images import clipped_codes, read_linear_image

    rgb = read_linear_image(path)
    clipped = clipped_codes(path)
    if clipped is None:
        clipped = np.zeros(rgb.shape, np.int8)
    return rgb, clipped, _alpha(Path(path), rgb.shape[:2])


def _alpha(path: Path, shape) -> np.ndarray:
    if path.suffix.lower() == ".npy":
        array = np.load(path, allow_pickle=False)
        return np.asarray(array[..., 3] > 0.5) if array.ndim == 3 and array.shape[2] >= 4 else np.ones(shape, bool)
    from explorer.views.env import _cv2

    cv2 = _cv2()
    pixels = cv2.imdecode(np.fromfile(path, dtype=np.uint8), cv2.IMREAD_UNCHANGED)
    if pixels is None or pixels.ndim != 3 or pixels.shape[2] < 4:
        return np.ones(shape, bool)
    alpha = pixels[..., 3].astype(np.float64)
    if np.issubdtype(pixels.dtype, np.integer):
        alpha /= np.iinfo(pixels.dtype).max
    return alpha > 0.5
