"""
Spatially varying film thickness (Belcour & Barla 2017, Section 5 and Figures 12-15): a grey texture
remaps the OPD at normal incidence ``D_inc`` over ``[min, max]`` nm, shown by the ``textured`` view.

Parametrisation (planar, the orthographic projection of the ``lit`` view's sphere): the pixel at
``p = (x, y)`` in ``[-1, 1]^2`` (``p = 2 gl_FragCoord.xy / resolution - 1``) reads the texture at
``u = (x + 1) / 2`` across and ``v = (1 - y) / 2`` down (image rows from the top), bilinearly between
texel centres ``((k + 1/2) / W_t, (l + 1/2) / H_t)``, clamped to the edge texels. No inverse
trigonometry, so float32 GLSL and numpy read the same value.

Prefiltering (Section 5, Multi-scale Rendering): the footprint of pixel ``(i, j)`` in texture space is
exactly the square ``u in [i, i + 1] / W``, ``v in [j, j + 1] / H`` (the mapping is affine in the pixel
grid). The host computes the mean and variance of ``D_inc`` over it, by the midpoint rule on an
``S x S`` grid of the bilinear texture with ``S = ceil(4 max(W_t, H_t) / min(W, H))`` (4 samples per texel, at most 32),
and hands both to the shader as a per-pixel texture; the shader shades the mean film with the Fourier
table pre-filtered by that variance (:func:`explorer.physics.thinfilm.fourier_rgb_prefiltered`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from explorer.errors import LocatedError
from explorer.resources import DEFAULT_TEXTURE
from explorer.materials.thinfilm_model import TABULATED_FOURIER

#: ``--dinc-range`` default (nm of D_inc): the paper's Figure 13 remaps its texture over [0, 1125] nm.
DEFAULT_DINC_RANGE = (0.0, 1125.0)
#: The largest D_inc (nm) ``--dinc-range`` accepts: the OPD at normal incidence, 2 eta_2 d, of the thickest
#: film shaders/thin_film.brd declares (d <= 3000 nm, eta2 <= 3); the Fourier table reaches 40950 nm.
DINC_MAX = 18000.0
#: Methods the prefiltering applies to: the tabulated Fourier ones (Eq. 10 with the pre-filtered table).
PREFILTER_METHODS = tuple(int(m) for m in TABULATED_FOURIER)
MAX_FOOTPRINT_SAMPLES = 32


def generate_default_texture(size: int = 128, seed: int = 5) -> np.ndarray:
    """
    The default thickness texture, ``shaders/textures/thickness_noise.png``: value noise (four octaves
    of bilinearly upsampled uniform noise, amplitudes halving), normalised to 0..255, ``uint8 (size, size)``.
    Deterministic (numpy's PCG64 with ``seed``).
    """
    rng = np.random.default_rng(seed)
    total = np.zeros((size, size))
    for octave, cells in enumerate((4, 8, 16, 32)):
        grid = rng.random((cells + 1, cells + 1))
        t = np.linspace(0.0, cells, size, endpoint=False)
        i = np.floor(t).astype(int)
        f = t - i
        f = f * f * (3.0 - 2.0 * f)
        rows = grid[i] * (1.0 - f)[:, None] + grid[i + 1] * f[:, None]
        total += 0.5**octave * (rows[:, i] * (1.0 - f)[None, :] + rows[:, i + 1] * f[None, :])
    total = (total - total.min()) / (total.max() - total.min())
    return np.round(255.0 * total).astype(np.uint8)


def write_default_texture(path: Path = DEFAULT_TEXTURE) -> Path:
    """Write :func:`generate_default_texture` as an 8-bit grey PNG (``python -m explorer.views.thickness``)."""
    from PIL import Image

    path.parent.mkdir(parents=True, exist_ok=True)
    from explorer.files import atomic_output

    with atomic_output(path, (".png",)) as temporary:
        Image.fromarray(generate_default_texture(), mode="L").save(temporary, format="PNG")
    return path


def load_grey(path: str | Path) -> np.ndarray:
    """
    A grey image (any format Pillow reads; colour images are converted to luma) as float64 in [0, 1],
    rows from the top; 16-bit images keep their precision. One-line :class:`LocatedError` naming the
    file when it is missing or not an image.
    """
    import warnings

    from PIL import Image, UnidentifiedImageError

    path = Path(path)
    try:
        with warnings.catch_warnings():
            # Pillow only warns between its limit and twice it: both are refused here (decompression bombs).
            warnings.simplefilter("error", Image.DecompressionBombWarning)
            image = Image.open(path)
        with image:
            image.load()
            if image.mode in ("I;16", "I;16B", "I;16L", "I"):
                grey = np.asarray(image, dtype=np.float64) / 65535.0
            elif image.mode == "F":
                grey = np.asarray(image, dtype=np.float64)
            else:
                grey = np.asarray(image.convert("L"), dtype=np.float64) / 255.0
    except FileNotFoundError:
        raise LocatedError(path, None, "thickness texture not found") from None
    except IsADirectoryError:
        raise LocatedError(path, None, "thickness texture is a directory, not an image") from None
    except UnidentifiedImageError:
        raise LocatedError(path, None, "thickness texture is not an image Pillow can read") from None
    except (Image.DecompressionBombError, Image.DecompressionBombWarning):
        raise LocatedError(path, None, f"thickness texture has more pixels than the limit, {Image.MAX_IMAGE_PIXELS} "
                                       "(PIL.Image.MAX_IMAGE_PIXELS, against decompression bombs)") from None
    except (OSError, ValueError, SyntaxError) as error:
        raise LocatedError(path, None, f"thickness texture cannot be read ({' '.join(str(error).split())})") from None
    if grey.ndim != 2 or grey.size == 0 or not np.all(np.isfinite(grey)):
        raise LocatedError(path, None, "thickness texture is not a non-empty grey image")
    return np.clip(grey, 0.0, 1.0)


def parse_dinc_range(text: str | None) -> tuple[float, float]:
    """``MIN,MAX`` in nm of D_inc, ``0 <= MIN <= MAX``, finite; :class:`LocatedError` otherwise."""
    if text is None:
        return DEFAULT_DINC_RANGE
    try:
        low, high = (float(part) for part in text.split(","))
    except ValueError:
        raise LocatedError("--dinc-range", None, f"{text[:60]!r} is not MIN,MAX in nm of D_inc (e.g. 0,1125)") from None
    if not (math.isfinite(low) and math.isfinite(high)) or not 0.0 <= low <= high <= DINC_MAX:
        raise LocatedError("--dinc-range", None, f"{text[:60]!r}: need 0 <= MIN <= MAX <= {DINC_MAX:g} (nm of D_inc)")
    return low, high


@dataclass
class ThicknessTexture:
    """``d_inc``: float32 ``(H_t, W_t)`` D_inc in nm, rows from the top; ``prefilter``: Section 5's filtering."""

    d_inc: np.ndarray
    prefilter: bool = False
    #: Where it came from (messages name it).
    source: str = "<array>"

    @classmethod
    def from_file(cls, path: str | Path = DEFAULT_TEXTURE, dinc_range=DEFAULT_DINC_RANGE, prefilter: bool = False):
        low, high = dinc_range
        return cls((low + (high - low) * load_grey(path)).astype(np.float32), bool(prefilter), str(path))

    def sample(self, u: np.ndarray, v: np.ndarray) -> np.ndarray:
        """Bilinear D_inc at ``(u, v)`` (float32 arithmetic for the coordinates, as the shader's)."""
        f32 = np.float32
        h, w = self.d_inc.shape
        tx = np.clip(np.asarray(u, f32) * f32(w) - f32(0.5), f32(0.0), f32(w - 1))
        ty = np.clip(np.asarray(v, f32) * f32(h) - f32(0.5), f32(0.0), f32(h - 1))
        i = np.minimum(np.floor(tx).astype(np.int64), max(w - 2, 0))
        j = np.minimum(np.floor(ty).astype(np.int64), max(h - 2, 0))
        fx = (tx - i.astype(f32)).astype(np.float64)
        fy = (ty - j.astype(f32)).astype(np.float64)
        i1, j1 = np.minimum(i + 1, w - 1), np.minimum(j + 1, h - 1)
        t = self.d_inc.astype(np.float64)
        top = t[j, i] * (1.0 - fx) + t[j, i1] * fx
        bottom = t[j1, i] * (1.0 - fx) + t[j1, i1] * fx
        return top * (1.0 - fy) + bottom * fy

    def footprint_samples(self, width: int) -> int:
        return int(min(MAX_FOOTPRINT_SAMPLES, max(1, math.ceil(4.0 * max(self.d_inc.shape) / width))))

    def moments(self, width: int, height: int) -> np.ndarray:
        """Per pixel (rows from the top): mean and variance of D_inc over its footprint, float32 ``(H, W, 2)``."""
        s = self.footprint_samples(min(width, height))
        offsets = (np.arange(s) + 0.5) / s
        u = (np.arange(width)[:, None] + offsets[None, :]).ravel() / width
        v = (np.arange(height)[:, None] + offsets[None, :]).ravel() / height
        values = self.sample(u[None, :], v[:, None]).reshape(height, s, width, s)
        mean = values.mean(axis=(1, 3))
        variance = np.maximum(((values - mean[:, None, :, None]) ** 2).mean(axis=(1, 3)), 0.0)
        return np.stack([mean, variance], axis=-1).astype(np.float32)

    def gl_inputs(self, width: int, height: int) -> dict[str, np.ndarray]:
        """The textures of ``shaders/views/textured.glsl`` (rows from the top)."""
        moments = self.moments(width, height) if self.prefilter else np.zeros((1, 1, 2), np.float32)
        return {"surface_texture": self.d_inc[..., None], "surface_moments": moments}

    def model_options(self) -> dict:
        """Keyword arguments of the model's ``textured_brdf`` besides the per-pixel values: none."""
        return {}

    def gl_arguments(self, material, values, width: int, height: int) -> dict:
        """``inputs`` and ``uniforms`` of :meth:`explorer.gpu.Renderer.render` for the textured view."""
        return {"inputs": self.gl_inputs(width, height), "uniforms": {"prefilter": self.prefilter}}

    def per_pixel(self, x: np.ndarray, y: np.ndarray, width: int, height: int) -> tuple[np.ndarray, np.ndarray]:
        """``(D_inc, sigma)`` at the pixels ``p = (x, y)`` (float32, as ``_disc``) of a ``(height, width)`` image."""
        if self.prefilter:
            moments = self.moments(width, height).astype(np.float64)
            return moments[..., 0], np.sqrt(moments[..., 1])
        f32 = np.float32
        u = f32(0.5) * (x + f32(1.0))
        v = f32(0.5) * (f32(1.0) - y)
        return self.at_uv(u, v)

    def at_uv(self, u: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(D_inc, 0)`` at texture coordinates ``(u, v)`` (a mesh's; the shader's ``surface_at``), unfiltered by any footprint."""
        return self.sample(u, v), np.zeros(np.shape(u))


def check_prefilter(method: int, prefilter: bool) -> None:
    if prefilter and method not in PREFILTER_METHODS:
        names = ", ".join(f"{int(m)} ({m.label})" for m in TABULATED_FOURIER)
        raise LocatedError("--prefilter", None, f"prefiltering needs a tabulated Fourier method ({names}), not method {method}")


if __name__ == "__main__":  # pragma: no cover
    from explorer.resources import require_checkout

    require_checkout("python -m explorer.views.thickness")
    print(write_default_texture())
