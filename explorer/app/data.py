"""
The explorer app's plots and comparisons, in numpy (no GUI): the spectrum of Figure 3 at one angle,
the polar plot from the scatter view, the ΔE2000 heat-map of a comparison.

Everything comes from the project's physics (:mod:`explorer.physics.bragg`) and colorimetry; nothing here is a
second implementation of a formula.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from explorer.physics import bragg, colorimetry
from explorer.materials.methods import BraggMethod, methods_for
from explorer.materials.models import mirror_of
from explorer.materials.twins import capabilities_of

#: The gradient rows of Figure 4, one per method in the methods' order (as the combo and ``info`` list them).
BRAGG_STRIP_METHODS = tuple(sorted(BraggMethod))


def method_names(material) -> dict[int, str]:
    """``{value: name}`` of a material's ``method`` parameter ({} without one)."""
    try:
        parameter = material.parameter("method")
    except KeyError:
        return {}
    methods = methods_for(material.model)
    known = {int(m): m.label for m in methods} if methods else {}
    return {m: known.get(m, f"method {m}") for m in range(int(parameter.min), int(parameter.max) + 1)}


def has_bragg_spectrum(material) -> bool:
    """Whether the material's values describe one Bragg mirror (n1, n2, Lambda, delta, N, nh): its twin declares
    ``bragg_spectrum`` (:mod:`explorer.materials.twins`); it gets a spectrum and the methods' strips."""
    return capabilities_of(material).bragg_spectrum


@dataclass
class Spectrum:
    """R_lambda at one angle and its approximation's structure, per polarisation (``'s'``, ``'p'``)."""

    wavelengths: np.ndarray
    R: dict[str, np.ndarray]
    envelope: dict[str, np.ndarray]
    gaps: list[tuple[float, float]] = field(default_factory=list)  # band gaps (nm) of either polarisation
    landmarks: np.ndarray = field(default_factory=lambda: np.zeros(0))  # nm
    boxes: dict[str, list[tuple[float, float, float]]] = field(default_factory=dict)  # (nm low, nm high, weight)


def _in_visible(nm_low, nm_high) -> bool:
    return nm_high > bragg.WAVELENGTH_LOW and nm_low < bragg.WAVELENGTH_HIGH


def spectrum(values, theta_degrees: float, method: int | None = None, s: int = 3, structure: bool = True) -> Spectrum:
    """
    The mirror's spectrum at incidence ``theta_degrees`` (Figure 3): ``R_s``, ``R_p`` (their average is
    what the eye sees), the envelope ``R^e``, the band gaps, the landmarks (the boundaries of the basic
    approximation's boxes: modes, band edges, Airy and zero points) and the boxes of ``method`` (1 basic,
    2 subdivided, 4 improved; none for the others).

    ``structure=False``: the curves alone (~2 ms; the landmarks' bisections take ~10 ms per polarisation
    and box set, too much for every frame of a slider drag).
    """
    mirror = mirror_of(values)
    cos_theta = np.array([np.cos(np.radians(min(max(theta_degrees, 0.0), 89.9)))])
    wavelengths = colorimetry.WAVELENGTHS
    omega = 2.0 * np.pi / wavelengths
    result = Spectrum(wavelengths, {}, {})
    landmarks: list[float] = []
    for polarisation in bragg.POLARISATIONS:
        geometry = bragg.cell_geometry(cos_theta, mirror, polarisation)
        rows = bragg.cell_geometry(np.full(omega.shape, cos_theta[0]), mirror, polarisation)
        result.R[polarisation] = bragg.reflectance_polarised(omega, rows)
        result.envelope[polarisation] = bragg.reflectance_envelope(omega, rows)
        if not structure:
            continue
        for low, high, weight, active in bragg.piecewise_constant_boxes(geometry, 0):
            if not active[0]:
                continue
            nm_low, nm_high = float(bragg.wavelength_of(high)[0]), float(bragg.wavelength_of(low)[0])
            if not _in_visible(nm_low, nm_high):
                continue
            landmarks.extend(x for x in (nm_low, nm_high) if bragg.WAVELENGTH_LOW <= x <= bragg.WAVELENGTH_HIGH)
            if np.all(weight == 1.0) and high[0] > low[0]:  # the gap halves have unit weight
                result.gaps.append((nm_low, nm_high))
        if method in (BraggMethod.BASIC, BraggMethod.SUBDIVIDED, BraggMethod.IMPROVED):
            subdivisions = 0 if method == BraggMethod.BASIC else s
            variant = "improved" if method == BraggMethod.IMPROVED else "paper"
            boxes = []
            for low, high, weight, active in bragg.piecewise_constant_boxes(geometry, subdivisions, variant=variant):
                nm_low, nm_high = float(bragg.wavelength_of(high)[0]), float(bragg.wavelength_of(low)[0])
                if active[0] and nm_high > nm_low and _in_visible(nm_low, nm_high):
                    boxes.append((max(nm_low, bragg.WAVELENGTH_LOW), min(nm_high, bragg.WAVELENGTH_HIGH), float(weight[0])))
            result.boxes[polarisation] = boxes
    result.landmarks = np.unique(np.round(np.array(landmarks), 2))
    return result


def boxes_polyline(boxes: list[tuple[float, float, float]]) -> tuple[np.ndarray, np.ndarray]:
    """A step line through boxes (nm low, nm high, weight), for plotting."""
    xs, ys = [], []
    for low, high, weight in sorted(boxes):
        xs += [low, high]
        ys += [weight, weight]
    return np.array(xs, dtype=np.float64), np.array(ys, dtype=np.float64)


def polar_curve(scatter_row: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """
    The BRDF in the plane of incidence from a ``(1, W, 3)`` scatter view rendered at height 1.

    At height 1 the scatter view's only row lies at y = 0: pixel x in (-1, 1) is the outgoing direction
    at ``theta_o = 90 |x|`` degrees in the plane of incidence (phi = 0 for x > 0, 180 for x < 0), and it
    shows ``BRDF cos theta_o``. Returns the signed ``theta_o`` (degrees, negative toward phi = 180) and
    the BRDF ``(W, 3)`` (``cos theta_o`` divided out).
    """
    row = np.asarray(scatter_row, dtype=np.float64).reshape(-1, 3)
    width = row.shape[0]
    x = 2.0 * (np.arange(width) + 0.5) / width - 1.0
    theta = 90.0 * x
    cos_theta = np.cos(np.radians(theta))
    return theta, row / np.maximum(cos_theta, 1e-3)[:, None]


#: The Polar window's log scale: radius log10(1 + x / floor), decades above this value (1/sr, or a reflectance).
#: BRDF Explorer's log10(1 + x) (floor 1) squeezes a GGX lobe of 0.2 / sr beside a Bragg lobe of 5 / sr to
#: 0.08 / 0.8; above 0.01 they are 1.3 / 2.7: both visible, their ratio still read in decades.
POLAR_LOG_FLOOR = 0.01


def polar_radius(brdf: np.ndarray, log: bool = False, normalise: bool = False) -> np.ndarray:
    """
    The Polar window's radius of a curve's values (negative ones, outside sRGB, as 0): ``normalise`` divides by
    the curve's own peak (each material's lobe fills the plot); ``log`` is ``log10(1 + x / POLAR_LOG_FLOOR)``, the
    decades above :data:`POLAR_LOG_FLOOR` (a wide, dim lobe stays visible beside a narrow, bright one).
    Normalised then logged: ``log10(1 + (x / peak) / POLAR_LOG_FLOOR)``.
    """
    r = np.clip(np.asarray(brdf, dtype=np.float64), 0.0, None)
    if normalise:
        peak = float(r.max()) if r.size else 0.0
        r = r / peak if peak > 0.0 else r
    return np.log10(1.0 + r / POLAR_LOG_FLOOR) if log else r


def polar_limits(curves, margin: float = 0.05) -> tuple[float, float, float, float]:
    """
    The Polar plot's axes ``(x_min, x_max, y_min, y_max)``: every point of ``curves`` (pairs of x and y arrays) inside,
    with ``margin`` of the span around, as a square (the plot keeps its aspect: a lobe is not stretched, nor cut).
    """
    xs = np.concatenate([np.asarray(x, dtype=np.float64).ravel() for x, _ in curves] + [np.zeros(1)])
    ys = np.concatenate([np.asarray(y, dtype=np.float64).ravel() for _, y in curves] + [np.zeros(1)])
    x0, x1, y0, y1 = float(xs.min()), float(xs.max()), float(ys.min()), float(ys.max())
    half = 0.5 * max(x1 - x0, y1 - y0, 1e-9) * (1.0 + 2.0 * margin)
    cx, cy = 0.5 * (x0 + x1), 0.5 * (y0 + y1)
    return cx - half, cx + half, cy - half, cy + half


def disc_mask(width: int, height: int) -> np.ndarray:
    """The pixels of the sphere views' disc (as the shaders test ``r^2 < 1``)."""
    from explorer.views.geometry import view_cos_theta

    return view_cos_theta("sphere", width, height)[1]


def delta_e_map(a: np.ndarray, b: np.ndarray, mask: np.ndarray | None = None) -> tuple[np.ndarray, float]:
    """ΔE2000 per pixel between two linear RGB images (0 outside ``mask``) and its mean over ``mask``."""
    mask = np.ones(a.shape[:2], dtype=bool) if mask is None else mask
    result = np.zeros(a.shape[:2])
    if mask.any():
        result[mask] = colorimetry.delta_E_2000(np.asarray(a, np.float64)[mask], np.asarray(b, np.float64)[mask])
    return result, float(result[mask].mean()) if mask.any() else 0.0


#: The ΔE2000 at the top of the heat-map's colour scale (and of its colour bar).
HEAT_MAP_TOP = 10.0


def heat_map_rgba(delta_e: np.ndarray, top: float = HEAT_MAP_TOP) -> np.ndarray:
    """An 8-bit RGBA image of ΔE2000 (matplotlib's viridis over [0, ``top``])."""
    from matplotlib import colormaps

    rgba = colormaps["viridis"](np.clip(delta_e / top, 0.0, 1.0))
    return np.round(rgba * 255.0).astype(np.uint8)


def slice_display(image: np.ndarray, exposure: float = 1.0, gamma: float = 2.2, chroma: bool = False) -> np.ndarray:
    """
    The Slice window's 8-bit RGBA picture of a linear BRDF slice, as BRDF Explorer's image slice shows it:
    ``(exposure x)^(1/gamma)`` clamped to [0, 1]; with ``chroma`` each pixel divided by its largest channel
    first (hue and saturation alone: where a lobe changes colour, not how bright it is). Rows as given.
    """
    rgb = np.nan_to_num(np.asarray(image, dtype=np.float64), nan=0.0, posinf=0.0, neginf=0.0)
    rgb = np.maximum(rgb, 0.0)  # out-of-gamut negatives: black, as the sRGB encode clamps them
    if chroma:
        peak = rgb.max(axis=-1, keepdims=True)
        rgb = np.divide(rgb, peak, out=np.zeros_like(rgb), where=peak > 0.0)
    else:
        rgb = rgb * exposure
    shown = np.clip(rgb, 0.0, 1.0) ** (1.0 / gamma)
    rgba = np.concatenate([shown, np.ones(shown.shape[:-1] + (1,))], axis=-1)
    return np.round(rgba * 255.0).astype(np.uint8)


def polar_incident(light, reach: float) -> tuple[np.ndarray, np.ndarray]:
    """
    The Polar window's incident direction: a segment from the origin to ``reach`` along the light ``(x, y, z)``
    projected on the plane of the curve (:func:`polar_curve`: x toward phi = 0, up the normal), as the curve's
    ``(r sin theta, r cos theta)``.
    """
    x, _, z = (float(c) for c in light)
    norm = max(float(np.hypot(x, z)), 1e-9)
    return np.array([0.0, reach * x / norm]), np.array([0.0, reach * z / norm])
