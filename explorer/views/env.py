"""
The ``env`` view in numpy: environment maps, the twins of the shader's random numbers and sampling, and
the exact integral by quadrature (the twin of the GPU's progressive Monte Carlo, :mod:`explorer.gpu.env`).

Each pixel shows ``L_o = int f(L, V) cos theta_L L_e(L) d omega_L`` over the hemisphere of its normal
``N``, with ``V = (0, 0, 1)`` and the lit view's geometry and frame (:func:`explorer.views.geometry.brdf_view_geometry`).

The environment is an equirectangular image of linear RGB radiance (:class:`EnvironmentMap`), read
from Radiance ``.hdr`` or OpenEXR ``.exr`` files by OpenCV. Its direction convention, shared with the
shader: the image's top row is the zenith ``+y`` (the sphere's screen up), ``v = theta / pi`` with
``theta`` the angle from ``+y``; the centre column ``u = 0.5`` looks away from the viewer (``-z``) and
``u = 0.75`` is ``+x``, so ``u = 0.5 + atan2(x, -z) / (2 pi)``. Lookups are bilinear between texel
centres, wrapping in ``u`` and clamped in ``v`` (GL's ``LINEAR`` with ``REPEAT`` / ``CLAMP_TO_EDGE``).

The GPU estimator is unbiased for any material: cosine sampling, or with a material's optional
``sampling_lobes`` hook one-sample MIS over GGX visible-normal lobes (Heitz 2018) and a cosine lobe,
the mixture density in the denominator (balance heuristic), and the environment's own luminance sampling in the
same mixture at each pixel's share (:func:`environment_share`: by its lobes' solid angles against the
environment's). The layered material's hook chooses
lobes by the layer probabilities of Eq. 35 (Fourneau et al. 2024); ``shaders/bragg_layer.brd`` uses
Eq. 31 for its one layer over the base.

References
----------
Fourneau, Pacanowski, Barla (2024), Section 4.2.3 and 4.3.2, Eqs. 31 and 35.
Heitz (2018). Sampling the GGX Distribution of Visible Normals. JCGT 7(4).
Veach (1997), PhD thesis, Section 9.2 (one-sample MIS, balance heuristic).
"""

from __future__ import annotations

import math
import os
from pathlib import Path
from typing import Callable

import numpy as np

from explorer.errors import LocatedError
from explorer.resources import DEFAULT_ENVIRONMENT

#: The file formats read (through OpenCV): Radiance RGBE and OpenEXR.
SUFFIXES = (".hdr", ".pic", ".exr")
#: The default environment: 256 x 128 texels (1.4 degrees each), a sky, a sun and a ground.
DEFAULT_SIZE = (256, 128)
#: The default sun: elevation and azimuth (degrees; azimuth from -z toward +x, so 180 is behind the
#: viewer), angular radius of its Gaussian profile (standard deviation, degrees), peak radiance. A broad,
#: dim sun: nothing samples the environment itself, and at a given irradiance a sun's variance grows as
#: the inverse of its solid angle.
SUN_ELEVATION, SUN_AZIMUTH, SUN_SIGMA, SUN_PEAK = 40.0, 145.0, 5.0, 12.0
#: Directions per block in the numpy quadrature (memory: a few arrays of this many 3-vectors).
QUADRATURE_BLOCK = 1 << 18
#: Quadrature cells per texel side at most (:func:`quadrature_subdivisions`).
MAX_SUBDIVISIONS = 16


class EnvironmentFileError(LocatedError):
    """An environment file is missing or not an HDR image (one line naming it)."""


def max_pixels() -> int:
    """The most pixels an input image may have: Pillow's decompression-bomb limit, for every format."""
    from PIL import Image

    return int(Image.MAX_IMAGE_PIXELS or 1 << 62)


def header_size(path: str | os.PathLike[str]) -> tuple[int, int] | None:
    """
    ``(width, height)`` from a Radiance ``.hdr`` header (its ``-Y H +X W`` resolution line) or an OpenEXR
    header (its ``dataWindow``), read before any pixel is decoded; None when the header is not one of those.
    """
    import re
    import struct

    with open(path, "rb") as stream:
        head = stream.read(1 << 16)
    if head[:4] == b"\x76\x2f\x31\x01":  # OpenEXR: attributes name\0 type\0 size value, until an empty name
        at = 8
        while at < len(head) and head[at] != 0:
            name_end = head.find(b"\0", at)
            type_end = head.find(b"\0", name_end + 1)
            if name_end < 0 or type_end < 0 or type_end + 5 > len(head):
                return None
            (size,) = struct.unpack_from("<i", head, type_end + 1)
            value = type_end + 5
            if head[at:name_end] == b"dataWindow" and size == 16 and value + 16 <= len(head):
                x0, y0, x1, y1 = struct.unpack_from("<4i", head, value)
                return x1 - x0 + 1, y1 - y0 + 1
            at = value + max(size, 0)
        return None
    found = re.search(rb"\n\n([-+][YX]) (\d{1,12}) ([-+][YX]) (\d{1,12})\s", head)
    if found is None:
        return None
    first, second = int(found.group(2)), int(found.group(4))
    return (second, first) if found.group(1).endswith(b"Y") else (first, second)


def _cv2():
    """OpenCV with OpenEXR enabled (it is off by default) and its own logging silenced (errors are ours)."""
    os.environ.setdefault("OPENCV_IO_ENABLE_OPENEXR", "1")
    os.environ.setdefault("OPENCV_IO_MAX_IMAGE_PIXELS", str(max_pixels()))  # the same limit as Pillow's
    import cv2

    cv2.utils.logging.setLogLevel(cv2.utils.logging.LOG_LEVEL_SILENT)
    return cv2


def opencv_rgb(pixels: np.ndarray) -> np.ndarray:
    """OpenCV's grey, BGR or BGRA pixels (as ``IMREAD_UNCHANGED`` gives them) as ``(H, W, 3)`` RGB, alpha dropped."""
    pixels = np.asarray(pixels)
    if pixels.ndim == 2:
        return np.repeat(pixels[..., None], 3, axis=-1)
    if pixels.ndim == 3 and pixels.shape[2] == 1:
        return np.repeat(pixels, 3, axis=-1)
    if pixels.ndim == 3 and pixels.shape[2] >= 3:
        return pixels[..., 2::-1]
    return pixels


# --------------------------------------------------------------------------------------------------
# Directions


def direction_to_uv(d) -> tuple[np.ndarray, np.ndarray]:
    """
    Texture coordinates of unit directions ``d`` (``(..., 3)``): ``u = 0.5 + atan2(x, -z) / 2 pi``,
    ``v = atan2(|(x, z)|, y) / pi`` (the shader's ``environment_radiance``; ``v = 0`` at ``+y``).
    """
    d = np.asarray(d, dtype=np.float64)
    u = 0.5 + np.arctan2(d[..., 0], -d[..., 2]) / (2.0 * np.pi)
    v = np.arctan2(np.hypot(d[..., 0], d[..., 2]), d[..., 1]) / np.pi
    return u, v


def uv_to_direction(u, v) -> np.ndarray:
    """The unit direction at texture coordinates ``(u, v)`` (inverse of :func:`direction_to_uv`)."""
    phi = 2.0 * np.pi * (np.asarray(u, dtype=np.float64) - 0.5)
    theta = np.pi * np.asarray(v, dtype=np.float64)
    phi, theta = np.broadcast_arrays(phi, theta)
    return np.stack([np.sin(theta) * np.sin(phi), np.cos(theta), -np.sin(theta) * np.cos(phi)], axis=-1)


def _bilinear_weights(coordinate: np.ndarray, size: int, wrap: bool) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """GL's LINEAR filter along one axis: texel indices ``i0, i1`` and the weight of ``i1``."""
    x = np.asarray(coordinate, dtype=np.float64) * size - 0.5
    i0 = np.floor(x)
    f = x - i0
    i0 = i0.astype(np.int64)
    i1 = i0 + 1
    if wrap:
        return np.mod(i0, size), np.mod(i1, size), f
    return np.clip(i0, 0, size - 1), np.clip(i1, 0, size - 1), f


# --------------------------------------------------------------------------------------------------
# The environment map


class EnvironmentMap:
    """
    An equirectangular environment: linear RGB radiance, ``(height, width, 3)`` float32, rows from the
    top (the zenith ``+y``); see the module's docstring for the direction convention.

    Parameters
    ----------
    pixels : array_like, shape (height, width, 3)
        Finite radiance values.
    name : str
        Where it comes from (a path), for messages.
    rotation : float
        The probe's turn about the vertical ``+y`` in degrees: the radiance toward ``d`` is the texel at
        ``u(d) - rotation / 360`` (the shader's ``environment_turn``; GL's ``REPEAT`` in ``u`` makes any
        turn exact under the bilinear lookup).
    """

    def __init__(self, pixels, name: str = "<array>", rotation: float = 0.0):
        data = np.ascontiguousarray(pixels, dtype=np.float32)
        if data.ndim != 3 or data.shape[2] != 3 or data.shape[0] < 1 or data.shape[1] < 1:
            raise EnvironmentFileError(name, None, f"environment must be an RGB image (height, width, 3), got shape {data.shape}")
        if not np.isfinite(data).all():
            raise EnvironmentFileError(name, None, "environment has non-finite (NaN or infinite) texels")
        data.setflags(write=False)
        self.pixels = data
        self.name = name
        if not math.isfinite(float(rotation)):
            raise EnvironmentFileError(name, None, f"environment rotation {rotation!r} is not a finite angle")
        self.rotation = float(rotation)

    @property
    def turn(self) -> float:
        """:attr:`rotation` as a fraction of a turn in [0, 1) (the shader's ``environment_turn``)."""
        return (self.rotation / 360.0) % 1.0

    def rotated(self, degrees: float) -> "EnvironmentMap":
        """The same texels, the probe turned by ``degrees`` about ``+y``."""
        return EnvironmentMap(self.pixels, self.name, degrees)

    @property
    def width(self) -> int:
        return self.pixels.shape[1]

    @property
    def height(self) -> int:
        return self.pixels.shape[0]

    @classmethod
    def load(cls, path: str | os.PathLike[str]) -> "EnvironmentMap":
        """
        Read a Radiance ``.hdr`` (``.pic``) or OpenEXR ``.exr`` file (through OpenCV; an EXR's alpha is
        dropped, a grey one becomes RGB). Raises :class:`EnvironmentFileError`, one line naming the file,
        when it is missing, a directory, of another format, or not readable as an image.
        """
        path = Path(path)
        name = os.fspath(path)
        if path.suffix.lower() not in SUFFIXES:
            raise EnvironmentFileError(name, None, "environment must be a Radiance .hdr or an OpenEXR .exr file")
        if not path.exists():
            raise EnvironmentFileError(name, None, "environment file not found")
        if path.is_dir():
            raise EnvironmentFileError(name, None, "environment file is a directory, not an image")
        if not os.access(path, os.R_OK):
            raise EnvironmentFileError(name, None, "environment file is not readable")
        try:
            size = header_size(path)
        except OSError as error:
            raise EnvironmentFileError(name, None, f"environment file is not readable ({error.strerror or error})") from None
        if size is not None and size[0] * size[1] > max_pixels():
            raise EnvironmentFileError(name, None, f"a {size[0]}x{size[1]} environment has more pixels than the limit, "
                                                   f"{max_pixels()} (PIL.Image.MAX_IMAGE_PIXELS, against decompression bombs)")
        cv2 = _cv2()
        try:
            image = cv2.imread(name, cv2.IMREAD_UNCHANGED)
        except cv2.error as error:
            image, reason = None, " ".join(str(error).split())
        else:
            reason = None
        if image is None:
            what = "HDR" if path.suffix.lower() != ".exr" else "OpenEXR"
            raise EnvironmentFileError(name, None, f"environment file is not an {what} image OpenCV can read" + (f" ({reason})" if reason else ""))
        image = opencv_rgb(image)
        if image.dtype.kind != "f":
            raise EnvironmentFileError(name, None, f"environment file holds {image.dtype} values, not floating-point radiance")
        return cls(image, name)

    @classmethod
    def default(cls) -> "EnvironmentMap":
        """The environment shipped in the repository (:data:`DEFAULT_ENVIRONMENT`, :func:`generate_default_environment`)."""
        return cls.load(DEFAULT_ENVIRONMENT)

    def radiance(self, d) -> np.ndarray:
        """Bilinear radiance ``(..., 3)`` (float64) toward unit directions ``d``: the shader's lookup."""
        u, v = direction_to_uv(d)
        return self.radiance_uv(u - self.turn, v)

    def radiance_uv(self, u, v) -> np.ndarray:
        """Bilinear radiance at texture coordinates (GL's ``LINEAR``, ``REPEAT`` in u, ``CLAMP_TO_EDGE`` in v)."""
        j0, j1, fu = _bilinear_weights(u, self.width, wrap=True)
        i0, i1, fv = _bilinear_weights(v, self.height, wrap=False)
        p = self.pixels.astype(np.float64)
        top = p[i0, j0] * (1.0 - fu)[..., None] + p[i0, j1] * fu[..., None]
        bottom = p[i1, j0] * (1.0 - fu)[..., None] + p[i1, j1] * fu[..., None]
        return top * (1.0 - fv)[..., None] + bottom * fv[..., None]

    def quadrature(self, subdivisions: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """
        A midpoint rule over the sphere: each texel split into ``subdivisions``\\ ² cells of equal
        ``(u, v)`` extent.

        Returns
        -------
        directions : ndarray, shape (M, 3)
            The cells' centre directions.
        solid_angle : ndarray, shape (M,)
            Each cell's exact solid angle, ``dphi (cos theta_0 - cos theta_1)`` (they sum to 4 pi).
        radiance : ndarray, shape (M, 3)
            The bilinear radiance at the centres. With an even ``subdivisions`` every cell lies within
            one bilinear patch (patch edges pass through texel centres).
        """
        s = int(subdivisions)
        rows, columns = self.height * s, self.width * s
        v_edges = np.arange(rows + 1) / rows
        v = 0.5 * (v_edges[1:] + v_edges[:-1])
        u = (np.arange(columns) + 0.5) / columns
        band = (np.cos(np.pi * v_edges[:-1]) - np.cos(np.pi * v_edges[1:])) * (2.0 * np.pi / columns)
        directions = uv_to_direction(u[None, :] + self.turn, v[:, None]).reshape(-1, 3)  # texel (u, v) under the turn
        solid_angle = np.broadcast_to(band[:, None], (rows, columns)).reshape(-1)
        radiance = self.radiance_uv(u[None, :], v[:, None]).reshape(-1, 3)
        return directions, solid_angle, radiance


def generate_default_environment(width: int = DEFAULT_SIZE[0], height: int = DEFAULT_SIZE[1]) -> np.ndarray:
    """
    The default environment (``shaders/environments/default.hdr``): a procedural sky, deterministic.

    Above the horizon a sky from a pale horizon (radiance 1.1, 1.1, 1.05) to a blue zenith
    (0.25, 0.45, 0.95) as ``sqrt(sin elevation)``; below it a warm grey ground (0.32, 0.27, 0.22),
    darker straight down; a smooth transition over +-2 degrees; a sun of Gaussian profile
    (:data:`SUN_SIGMA` degrees, peak :data:`SUN_PEAK` times (1, 0.92, 0.8)) at :data:`SUN_ELEVATION`,
    :data:`SUN_AZIMUTH` (behind the viewer's right shoulder, so it lights the visible face). Evaluated at
    texel centres; ``(height, width, 3)`` float32.
    """
    u = (np.arange(width) + 0.5) / width
    v = (np.arange(height) + 0.5) / height
    d = uv_to_direction(u[None, :], v[:, None])
    up = d[..., 1]
    horizon, zenith = np.array([1.1, 1.1, 1.05]), np.array([0.25, 0.45, 0.95])
    t = np.sqrt(np.clip(up, 0.0, 1.0))[..., None]
    sky = horizon * (1.0 - t) + zenith * t
    ground = np.array([0.32, 0.27, 0.22]) * (0.55 + 0.45 * (1.0 + np.clip(up, -1.0, 0.0)))[..., None]
    edge = np.sin(np.radians(2.0))
    w = np.clip((up + edge) / (2.0 * edge), 0.0, 1.0)
    w = (w * w * (3.0 - 2.0 * w))[..., None]
    image = ground * (1.0 - w) + sky * w
    elevation, azimuth = np.radians(SUN_ELEVATION), np.radians(SUN_AZIMUTH)
    sun = np.array([np.cos(elevation) * np.sin(azimuth), np.sin(elevation), -np.cos(elevation) * np.cos(azimuth)])
    angle = np.arccos(np.clip(d @ sun, -1.0, 1.0))
    image += SUN_PEAK * np.array([1.0, 0.92, 0.8]) * np.exp(-0.5 * (angle / np.radians(SUN_SIGMA)) ** 2)[..., None]
    return image.astype(np.float32)


def studio_environment(width: int = 128, height: int = 64) -> EnvironmentMap:
    """
    A studio: a dim grey surround (0.05) and two soft rectangular lights, a warm key (radiance 6 x (1, 0.85,
    0.7)) up and to the viewer's right and a cool fill (1.5 x (0.6, 0.75, 1)) to the left, each 40 x 25
    degrees; generated, deterministic.
    """
    u = (np.arange(width) + 0.5) / width
    v = (np.arange(height) + 0.5) / height
    azimuth, elevation = np.meshgrid(360.0 * (u - 0.5), 90.0 - 180.0 * v)  # azimuth 0 looks away from the viewer
    image = np.full((height, width, 3), 0.05)
    for centre, colour in (((140.0, 35.0), (6.0, 5.1, 4.2)), ((-120.0, 15.0), (0.9, 1.125, 1.5))):
        inside = (np.abs((azimuth - centre[0] + 180.0) % 360.0 - 180.0) < 20.0) & (np.abs(elevation - centre[1]) < 12.5)
        image[inside] = colour
    return EnvironmentMap(image.astype(np.float32), "studio")


def white_furnace(width: int = 16, height: int = 8) -> EnvironmentMap:
    """Radiance 1 everywhere: the env view then shows each pixel's directional albedo (an energy check)."""
    return EnvironmentMap(np.ones((height, width, 3), np.float32), "white furnace")


#: The environments by name (``render --env NAME``, the app's choice): the shipped sky and two generated ones.
ENVIRONMENTS: dict[str, Callable[[], EnvironmentMap]] = {
    "sky": lambda: EnvironmentMap.default(),
    "studio": studio_environment,
    "white furnace": white_furnace,
}


def environment_named(text: str | os.PathLike[str]) -> EnvironmentMap:
    """``--env``: one of :data:`ENVIRONMENTS` by name (where no such file exists), else a ``.hdr`` or ``.exr`` file."""
    text = os.fspath(text)
    if text in ENVIRONMENTS and not Path(text).exists():
        return ENVIRONMENTS[text]()
    return EnvironmentMap.load(text)


def write_default_environment(path: Path = DEFAULT_ENVIRONMENT) -> Path:
    """Write :func:`generate_default_environment` as Radiance RGBE (``python -m explorer.views.env``)."""
    cv2 = _cv2()
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    from explorer.files import atomic_output

    with atomic_output(path) as temporary:
        if not cv2.imwrite(os.fspath(temporary), generate_default_environment()[:, :, ::-1]):
            raise OSError(f"{path}: OpenCV could not write it")
    return path


# --------------------------------------------------------------------------------------------------
# Twins of the shader's random numbers and cosine sampling (shaders/lib/sampling.glsl)


def pcg4d(v) -> np.ndarray:
    """The shader's PCG4D hash (Jarzynski & Olano 2020) on ``uint32 (..., 4)``: bit for bit the same."""
    v = np.array(v, dtype=np.uint32)
    with np.errstate(over="ignore"):
        v = v * np.uint32(1664525) + np.uint32(1013904223)
        x, y, z, w = (v[..., k].copy() for k in range(4))
        for _ in range(2):
            x += y * w
            y += z * x
            z += x * y
            w += y * z
            if _ == 0:
                x ^= x >> np.uint32(16)
                y ^= y >> np.uint32(16)
                z ^= z >> np.uint32(16)
                w ^= w >> np.uint32(16)
    return np.stack([x, y, z, w], axis=-1)


def uniform_floats(h) -> np.ndarray:
    """The top 24 bits of each word as floats in [0, 1) (the shader's ``uniform_floats``)."""
    return (np.asarray(h, dtype=np.uint32) >> np.uint32(8)).astype(np.float64) / 16777216.0


def sample_cosine_hemisphere(u1, u2) -> np.ndarray:
    """Malley's method about ``+z``: density ``cos theta / pi`` (the shader's ``sample_cosine_hemisphere``)."""
    r, phi = np.sqrt(u1), 2.0 * np.pi * np.asarray(u2, dtype=np.float64)
    return np.stack([r * np.cos(phi), r * np.sin(phi), np.sqrt(np.maximum(0.0, 1.0 - np.asarray(u1)))], axis=-1)


# --------------------------------------------------------------------------------------------------
# Twins of the environment's importance sampling (shaders/lib/sampling.glsl)

#: Luminance of linear sRGB (Rec. 709 Y): what the environment's texels are sampled in proportion to.
LUMINANCE = np.array([0.2126, 0.7152, 0.0722])


def environment_sampling_tables(environment: EnvironmentMap) -> tuple[np.ndarray, np.ndarray]:
    """
    The two CDFs of the environment's sampling (Pharr et al., PBRT 3, Sec. 14.2.4), float32 as the shader's
    textures: ``marginal`` ``(1, H + 1)`` over rows and ``conditional`` ``(H, W + 1)`` over each row's texels,
    of ``max(luminance, 0) sin(theta)`` per texel (``theta`` at the row's centre); a black environment (or
    row) is sampled uniformly in ``(u, v)`` times ``sin(theta)``.
    """
    height, width = environment.height, environment.width
    sin_theta = np.sin(np.pi * (np.arange(height) + 0.5) / height)
    weight = np.maximum(environment.pixels.astype(np.float64) @ LUMINANCE, 0.0) * sin_theta[:, None]
    if weight.sum() <= 0.0:
        weight = np.broadcast_to(sin_theta[:, None], (height, width)).copy()
    rows = weight.sum(axis=1)
    blank = rows <= 0.0
    weight[blank] = 1.0  # a black row is never chosen (its marginal mass is 0): any conditional will do
    conditional = np.concatenate([np.zeros((height, 1)), np.cumsum(weight, axis=1)], axis=1)
    conditional /= conditional[:, -1:]
    marginal = np.concatenate([[0.0], np.cumsum(rows)]) / rows.sum()
    conditional[:, -1] = 1.0
    marginal[-1] = 1.0
    return marginal[None, :].astype(np.float32), conditional.astype(np.float32)


def sample_environment(tables, turn: float, u1, u2) -> np.ndarray:
    """Directions ``(..., 3)`` for uniform ``u1``, ``u2`` (the shader's ``sample_environment``, in float64 on the float32 CDFs)."""
    marginal, conditional = (np.asarray(t, np.float64) for t in tables)
    marginal = marginal[0]
    rows, columns = conditional.shape[0], conditional.shape[1] - 1
    u1, u2 = np.asarray(u1, np.float64), np.asarray(u2, np.float64)
    i = np.clip(np.searchsorted(marginal, u1, side="right") - 1, 0, rows - 1)
    fv = np.clip((u1 - marginal[i]) / np.maximum(marginal[i + 1] - marginal[i], 1e-30), 0.0, 1.0)
    cdf = conditional[i]
    j = np.clip(np.sum(cdf <= u2[..., None], axis=-1) - 1, 0, columns - 1)
    c0, c1 = np.take_along_axis(cdf, j[..., None], -1)[..., 0], np.take_along_axis(cdf, j[..., None] + 1, -1)[..., 0]
    fu = np.clip((u2 - c0) / np.maximum(c1 - c0, 1e-30), 0.0, 1.0)
    return uv_to_direction((j + fu) / columns + turn, (i + fv) / rows)


def environment_pdf(tables, turn: float, d) -> np.ndarray:
    """The density in solid angle of :func:`sample_environment` toward unit ``d`` (the shader's ``environment_pdf``)."""
    marginal, conditional = (np.asarray(t, np.float64) for t in tables)
    marginal = marginal[0]
    rows, columns = conditional.shape[0], conditional.shape[1] - 1
    d = np.asarray(d, np.float64)
    u, v = direction_to_uv(d)
    u = np.mod(u - turn, 1.0)
    i = np.clip((v * rows).astype(np.int64), 0, rows - 1)
    j = np.clip((u * columns).astype(np.int64), 0, columns - 1)
    mass = (marginal[i + 1] - marginal[i]) * (conditional[i, j + 1] - conditional[i, j])
    sin_theta = np.hypot(d[..., 0], d[..., 2])
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(sin_theta > 1e-7, mass * rows * columns / (2.0 * np.pi ** 2 * sin_theta), 0.0)


#: The largest share of environment samples (a lobe much broader than the environment's bright parts).
ENVIRONMENT_SHARE_MAX = 0.75
#: x = ENVIRONMENT_SHARE_SCALE Omega_lobe / Omega_env in the share w_max x / (1 + x) (:func:`environment_share`).
#: Fitted: GGX lobes of alpha 0.02 to 1 under the sky and the studio, 512 spp, the share that minimises the
#: RMS standard error; this rule's error stays within 3 % of the best share's (docs/meshes.md).
ENVIRONMENT_SHARE_SCALE = 3.0


def environment_solid_angle(environment: EnvironmentMap) -> float:
    """
    The environment's effective solid angle (sr): ``(int Y d omega)^2 / int Y^2 d omega`` of its luminance ``Y``
    over the sphere (texel by texel, each texel's exact solid angle); ``4 pi`` for a uniform environment, the
    solid angle of a light for one small uniform light on black, ``4 pi`` for a black one.
    """
    height, width = environment.height, environment.width
    edges = np.pi * np.arange(height + 1) / height
    texel = (np.cos(edges[:-1]) - np.cos(edges[1:])) * (2.0 * np.pi / width)
    Y = np.maximum(environment.pixels.astype(np.float64) @ LUMINANCE, 0.0)
    first, second = float(np.sum(Y.sum(axis=1) * texel)), float(np.sum((Y * Y).sum(axis=1) * texel))
    return first * first / second if second > 0.0 else 4.0 * np.pi


def lobe_solid_angle(alpha) -> np.ndarray:
    """A GGX lobe's solid angle for :func:`environment_share`: ``min(4 pi alpha^2, 2 pi)`` (the reflected lobe, Jacobian 4 at normal incidence)."""
    alpha = np.asarray(alpha, dtype=np.float64)
    return np.minimum(4.0 * np.pi * alpha * alpha, 2.0 * np.pi)


def environment_share(alphas, weights, cosine_weight: float, environment: EnvironmentMap | float,
                      most: float = ENVIRONMENT_SHARE_MAX) -> float:
    """
    The share of a pixel's samples drawn from the environment (the twin of ``environment_share`` in
    ``shaders/views/env.glsl``): each lobe's ``most x / (1 + x)``, ``x`` = :data:`ENVIRONMENT_SHARE_SCALE` times
    its solid angle (:func:`lobe_solid_angle`; the cosine lobe ``2 pi``) over the environment's
    (:func:`environment_solid_angle`, or that number), weighted as the lobes are chosen (``weights``,
    ``cosine_weight``: normalised, as the material's ``sampling_lobes`` hook and the shader leave them).

    A sharp lobe under a broad sky takes mostly its own samples (a GGX lobe's visible normals are nearly
    exact there); a broad lobe under small bright lights mostly the environment's. Any share in [0, 1) keeps
    the one-sample MIS estimator unbiased (the mixture's density divides each sample); it only changes the variance.
    """
    omega_env = environment_solid_angle(environment) if isinstance(environment, EnvironmentMap) else float(environment)
    scale = ENVIRONMENT_SHARE_SCALE / omega_env

    def lobe(omega):
        x = scale * omega
        return most * x / (1.0 + x)

    weights = np.asarray(weights, dtype=np.float64)
    share = cosine_weight * lobe(2.0 * np.pi) + np.sum(np.where(weights > 0.0, weights * lobe(lobe_solid_angle(alphas)), 0.0))
    return float(share)


# --------------------------------------------------------------------------------------------------
# The numpy twin: the exact integral by quadrature


def _roughness(model) -> float | None:
    """The smallest GGX roughness of a model: its ``alpha``, or its stack's layers' (None for neither)."""
    alphas = [getattr(model, "alpha", None)]
    alphas += [getattr(layer, "alpha", None) for layer in getattr(getattr(model, "stack", None), "layers", ())]
    alphas = [float(a) for a in alphas if a is not None]
    return min(alphas) if alphas else None


def quadrature_subdivisions(model, environment: EnvironmentMap) -> int:
    """
    Cells per texel side for :func:`env_integral_numpy`: even, at least 2, and fine enough that a cell
    spans at most a quarter of the model's smallest GGX roughness (``model.alpha`` or its stack's
    layers' ``alpha``, in radians, where it has one), at most :data:`MAX_SUBDIVISIONS`.
    """
    texel = np.pi / environment.height
    s = 2
    alpha = _roughness(model)
    if alpha is not None and alpha > 0.0:
        s = max(s, math.ceil(texel / (0.25 * alpha)))
    s += s % 2
    return int(min(s, MAX_SUBDIVISIONS))


#: The backdrop's pinhole: the tangent of its half field of view (60 degrees across the shorter side).
BACKDROP_TAN = math.tan(math.radians(30.0))


def backdrop(environment: EnvironmentMap, width: int, height: int) -> np.ndarray:
    """
    The environment behind the object (the env view's ``show_background``): at pixel ``p`` (``2 (i + 1/2) - W``
    over the shorter side, rows from the top), the radiance toward ``normalize(p BACKDROP_TAN, -1)``, a
    pinhole looking along ``-z``; ``(height, width, 3)`` float64.
    """
    side = min(width, height)
    x = (2.0 * (np.arange(width) + 0.5) - width) / side
    y = (height - 2.0 * (np.arange(height) + 0.5)) / side
    X, Y = np.meshgrid(x * BACKDROP_TAN, y * BACKDROP_TAN)
    d = np.stack([X, Y, -np.ones_like(X)], axis=-1)
    return environment.radiance(d / np.linalg.norm(d, axis=-1, keepdims=True))


def env_integral_numpy(
    model, environment: EnvironmentMap, width: int, height: int, pixels=None, subdivisions: int | None = None,
    progress: Callable[[int, int], None] | None = None, mesh=None, background: bool = False, surface=None,
) -> np.ndarray:
    """
    The env view's exact value, ``int f(L, V) cos theta_L L_e(L) d omega_L`` per pixel, ``f`` under the
    views' rule (:func:`explorer.views.geometry.view_brdf`: 0 below the surface, NaN or infinite channels 0; plus a model's
    Dirac reflection, ``model.mirror_reflection(V, N) L_e(reflect(-V, N))``, when it has one), by a midpoint
    rule over the environment's texels (:meth:`EnvironmentMap.quadrature`, each cell's exact solid
    angle, the bilinear radiance the shader reads).

    Parameters
    ----------
    model
        A numpy twin from :mod:`explorer.materials.models` (``model.brdf(L, V, N, X, Y) -> (..., 3)``).
    environment : EnvironmentMap
    width, height : int
        The image size (the lit view's sphere: :func:`explorer.views.geometry.brdf_view_geometry`).
    pixels : array_like of (row, column), optional
        Only these pixels (rows from the top): the integral costs one BRDF evaluation per cell (about
        ``4 pi`` / 2 of ``(W_env H_env s^2)`` directions) per pixel.
    subdivisions : int, optional
        Cells per texel side (default :func:`quadrature_subdivisions`).
    progress : callable, optional
        ``progress(done, total)`` after each pixel.
    mesh : explorer.views.mesh.Mesh, optional
        Drawn instead of the sphere (its normals by :func:`explorer.views.mesh.rasterise`).
    background : bool
        Off the object, the environment behind it (:func:`backdrop`) instead of 0.
    surface : optional
        The material's surface texture (:mod:`explorer.views.surface_texture`): each pixel evaluates the model's
        ``textured_brdf`` (and ``textured_mirror_reflection``) at its texture value instead, unfiltered.

    Returns
    -------
    ndarray
        ``(P, 3)`` float64 for ``pixels`` (0 outside the disc), else the ``(height, width, 3)`` float32 image.
    """
    from explorer.views.geometry import brdf_view_geometry, view_brdf

    raster = None
    if mesh is not None:
        from explorer.views.mesh import mesh_view_geometry, rasterise

        raster = rasterise(mesh, width, height)
        _, V, N, X, Y, inside, _ = mesh_view_geometry(raster.normals, raster.covered)
    else:
        _, V, N, X, Y, inside, _ = brdf_view_geometry("lit", width, height)
    brdf, mirror = model.brdf, getattr(model, "mirror_reflection", None)
    value = None
    if surface is not None:  # the texture value per pixel, as the shader reads it (surface_at(surface_uv))
        from explorer.views.geometry import surface_values

        value = surface_values(surface, width, height, raster)[0]
        options = surface.model_options()
    if pixels is None:
        rows, columns = np.nonzero(inside)
    else:
        index = np.asarray(pixels, dtype=np.int64).reshape(-1, 2)
        rows, columns = index[:, 0], index[:, 1]
        if ((rows < 0) | (rows >= height) | (columns < 0) | (columns >= width)).any():
            raise ValueError(f"pixels must lie in the {width}x{height} image")
    s = quadrature_subdivisions(model, environment) if subdivisions is None else int(subdivisions)
    directions, solid_angle, radiance = environment.quadrature(s)
    weighted = radiance * solid_angle[:, None]
    values = np.zeros((rows.size, 3))
    mirror_only = bool(getattr(model, "mirror_only", False))  # a smooth mirror: the Dirac below, nothing else
    for k, (r, c) in enumerate(zip(rows, columns)):
        if value is not None:
            def brdf(L, V, N, X, Y, t=float(value[r, c])):
                return model.textured_brdf(L, V, N, X, Y, np.full(L.shape[:-1], t), np.zeros(L.shape[:-1]), False, **options)
        if inside[r, c] and not mirror_only:
            n = N[r, c].astype(np.float64)
            frame = [a[r, c].astype(np.float64) for a in (V, N, X, Y)]
            for start in range(0, directions.shape[0], QUADRATURE_BLOCK):
                block = directions[start:start + QUADRATURE_BLOCK]
                cos_l = block @ n
                above = cos_l > 0.0
                if not above.any():
                    continue
                L = block[above]
                f = view_brdf(brdf, L, *(np.broadcast_to(a, L.shape) for a in frame))
                values[k] += np.sum(f * (cos_l[above, None] * weighted[start:start + QUADRATURE_BLOCK][above]), axis=0)
        if progress is not None:
            progress(k + 1, rows.size)
    if mirror is not None:  # a Dirac (a smooth coating): its weight times the radiance of the mirror direction
        hit = inside[rows, columns]
        v, n = V[rows, columns][hit].astype(np.float64), N[rows, columns][hit].astype(np.float64)
        reflected = 2.0 * np.sum(v * n, axis=-1, keepdims=True) * n - v
        if value is not None and callable(getattr(model, "textured_mirror_reflection", None)):
            weight = model.textured_mirror_reflection(v, n, value[rows, columns][hit], **options)
        else:
            weight = mirror(v, n)
        values[hit] += weight * environment.radiance(reflected)
    if background:
        off = ~inside[rows, columns]
        values[off] = backdrop(environment, width, height)[rows[off], columns[off]]
    if pixels is not None:
        return values
    image = np.zeros((height, width, 3), dtype=np.float32)
    if background:
        image[:] = backdrop(environment, width, height)
    image[rows, columns] = values
    return image


if __name__ == "__main__":
    from explorer.resources import require_checkout

    require_checkout("python -m explorer.views.env")
    print(f"wrote {write_default_environment()}")
