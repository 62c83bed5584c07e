"""
glTF's one thin film (``KHR_materials_iridescence``) and the nearest such film to any material.

:func:`iridescent_fresnel` is the extension's ``iridescent_fresnel(outside_ior, iridescence_ior, base_f0,
thickness)`` at the view angle, as the Khronos specification writes it (section "Iridescence Fresnel"):
Schlick at both interfaces, phase shifts of 0 or pi, the Airy series summed to m = 2 in Fourier space with
Gaussian fits of the XYZ sensitivities, then XYZ -> Rec. 709. :func:`specular_reflectance` is the smooth
material's reflection under the specification's metallic-roughness model with the extension
(``iridescent_conductor_layer`` / ``iridescent_dielectric_layer`` over a black base colour): what a glTF
engine shows in the mirror direction.

A single film (``thin_film``) whose exterior is air and whose base is a dielectric of index >= 1 or a conductor maps
directly (:func:`direct_film`). Any other material gets the nearest film (:func:`fit_film`): the
thickness, film index, factor and metallic base colour minimising the ΔE2000 between
:func:`specular_reflectance` and the material's own ``reflectance(cos theta)`` over :data:`THETA_DEG`.
Both report the ΔE2000 per angle (docs/export.md).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from explorer.physics import colorimetry

#: The view angles over which a thin film's global fit takes its median (every degree of the hemisphere, so
#: that the fit leans on no reporting grid).
DENSE_THETA_DEG = np.arange(0.0, 90.0, 1.0)
#: The angles (degrees from the normal) at which a film is fitted and its ΔE2000 reported: every fifth.
_REPORTED = slice(None, None, 5)
THETA_DEG = DENSE_THETA_DEG[_REPORTED]
#: The global fit's objective: the mean of the middle of the sorted ΔE2000 (these quantiles) plus this weight
#: times their mean (of two films equally close at the median, the closer at the rim).
MEDIAN_BAND = (0.44, 0.56)
TAIL_WEIGHT = 0.02

# The specification's Gaussian fits of the XYZ sensitivities in Fourier space (evalSensitivity) and its
# XYZ -> Rec. 709 matrix (row-major here: rgb = M @ xyz).
_VAL = np.array([5.4856e-13, 4.4201e-13, 5.2481e-13])
_POS = np.array([1.6810e06, 1.7953e06, 2.2084e06])
_VAR = np.array([4.3278e09, 9.3046e09, 6.6121e09])
_XYZ_TO_REC709 = np.array([
    [3.2404542, -1.5371385, -0.4985314],
    [-0.9692660, 1.8760108, 0.0415560],
    [0.0556434, -0.2040259, 1.0572252],
])

#: The thickness (nm) and film index ranges the fit searches (the extension allows any thickness >= 0
#: and an index >= 1).
THICKNESS_RANGE = (0.0, 1500.0)
IOR_RANGE = (1.0, 3.0)
#: The dielectric's search: its grid's step in the optical path difference at normal incidence
#: (``D_inc = 2 n d``, nm), film indices (offsets from the film's own), base indices and factors; the grid's
#: best distinct starts polished; differential evolution's population per coordinate and generations.
GRID_OPD_STEP = 10.0
GRID_FILM_IOR_OFFSETS = (-0.3, -0.15, 0.0, 0.15, 0.3)
GRID_BASE_IORS = (1.0, 1.5, 2.0, 2.5, 3.0)
GRID_FACTORS = (0.4, 0.6, 0.8, 1.0)
POLISHED_STARTS = 4
EVOLUTION = (20, 200)


def _schlick(f0, cos):
    return f0 + (1.0 - f0) * (1.0 - cos) ** 5


def _ior_to_f0(transmitted, incident):
    return ((transmitted - incident) / (transmitted + incident)) ** 2


def _sensitivity(opd: np.ndarray, shift: np.ndarray) -> np.ndarray:
    """The specification's ``evalSensitivity``: ``opd`` (...,), ``shift`` (..., 3) -> Rec. 709 (..., 3)."""
    phase = (2.0 * np.pi * 1.0e-9 * opd)[..., None]
    xyz = _VAL * np.sqrt(2.0 * np.pi * _VAR) * np.cos(_POS * phase + shift) * np.exp(-phase**2 * _VAR)
    xyz[..., 0] += (9.7470e-14 * np.sqrt(2.0 * np.pi * 4.5282e09) * np.cos(2.2399e06 * phase[..., 0] + shift[..., 0])
                    * np.exp(-4.5282e09 * phase[..., 0] ** 2))
    return (xyz / 1.0685e-7) @ _XYZ_TO_REC709.T


def iridescent_fresnel(outside_ior, film_ior, base_f0, thickness, cos_theta) -> np.ndarray:
    """
    The extension's film Fresnel (linear Rec. 709, ``(..., 3)``) at ``cos_theta`` (broadcast with the
    scalars ``outside_ior``, ``film_ior``, ``thickness`` in nm and the RGB ``base_f0`` ``(..., 3)``).
    """
    cos1 = np.asarray(cos_theta, dtype=np.float64)
    outside, film = np.asarray(outside_ior, np.float64), np.asarray(film_ior, np.float64)
    thickness = np.asarray(thickness, np.float64)
    base_f0 = np.asarray(base_f0, np.float64)
    shape = np.broadcast_shapes(cos1.shape, outside.shape, film.shape, thickness.shape, base_f0.shape[:-1])
    cos1, outside, film, thickness = (np.broadcast_to(a, shape) for a in (cos1, outside, film, thickness))
    base_f0 = np.broadcast_to(base_f0, shape + (3,))
    sin2_sq = (outside / film) ** 2 * (1.0 - cos1**2)
    cos2_sq = 1.0 - sin2_sq
    tir = cos2_sq < 0.0
    cos2 = np.sqrt(np.maximum(cos2_sq, 0.0))
    # First interface.
    r12 = _schlick(_ior_to_f0(film, outside), cos1)[..., None]
    t121 = 1.0 - r12
    # Second interface: the base's index from its F0 (guarded against 1).
    sqrt_f0 = np.sqrt(base_f0 + 0.0001)
    base_ior = (1.0 + sqrt_f0) / (1.0 - sqrt_f0)
    r23 = _schlick(_ior_to_f0(base_ior, film[..., None]), cos2[..., None])
    opd = 2.0 * film * thickness * cos2
    phi12 = np.where(film < outside, np.pi, 0.0)[..., None]
    phi21 = np.pi - phi12
    phi23 = np.where(base_ior < film[..., None], np.pi, 0.0)
    phi = phi21 + phi23
    r123 = np.clip(r12 * r23, 1e-5, 0.9999)
    sqrt_r123 = np.sqrt(r123)
    rs = t121**2 * r23 / (1.0 - r123)
    intensity = r12 + rs
    cm = rs - t121
    for m in (1, 2):
        cm = cm * sqrt_r123
        intensity = intensity + cm * 2.0 * _sensitivity(m * opd, m * phi)
    return np.where(tir[..., None], 1.0, np.maximum(intensity, 0.0))


@dataclass
class Film:
    """The glTF parameters of one film over a black-based dielectric (``metallic`` 0) or a metal (1)."""

    thickness: float  # nm: iridescenceThicknessMaximum (no thickness texture)
    ior: float  # iridescenceIor
    factor: float  # iridescenceFactor
    metallic: float  # metallicFactor: 0 or 1
    base_color: tuple[float, float, float] = (0.0, 0.0, 0.0)  # baseColorFactor's RGB (the metal's F0)
    base_ior: float = 1.5  # KHR_materials_ior (the dielectric's)
    mapping: str = "direct"  # "direct" (a thin film), "refined" (from the direct one) or "fit" (the nearest film)
    delta_e: np.ndarray = field(default_factory=lambda: np.zeros(0))  # ΔE2000 at THETA_DEG
    direct: "Film | None" = None  # a refined film's direct mapping


def specular_reflectance(film: Film, cos_theta) -> np.ndarray:
    """The glTF material's smooth reflection at ``cos_theta`` (``(..., 3)``), black base colour for a dielectric."""
    cos = np.asarray(cos_theta, dtype=np.float64)
    if film.metallic >= 0.5:
        f0 = np.asarray(film.base_color, np.float64)
        plain = _schlick(f0, cos[..., None])  # conductor_fresnel
    else:
        # iridescent_dielectric_layer over a black base: F0 from KHR_materials_ior, Schlick's plain Fresnel, and
        # the film's second interface at the same F0.
        f0 = np.full(3, _ior_to_f0(film.base_ior, 1.0))
        plain = _schlick(f0, cos[..., None])
    iridescent = iridescent_fresnel(1.0, film.ior, f0, film.thickness, cos)
    return (1.0 - film.factor) * plain + film.factor * iridescent


def delta_e(film: Film, target_rgb: np.ndarray) -> np.ndarray:
    """ΔE2000 at :data:`THETA_DEG` between the film's reflection and ``target_rgb`` (``(len(THETA_DEG), 3)``)."""
    return colorimetry.delta_E_2000(specular_reflectance(film, np.cos(np.radians(THETA_DEG))), target_rgb)


def target_rgb(model, theta_deg: np.ndarray = THETA_DEG) -> np.ndarray:
    """A material twin's smooth reflectance at ``theta_deg`` (what its sphere and gradient views show)."""
    return np.asarray(model.reflectance(np.cos(np.radians(theta_deg))), dtype=np.float64)


def direct_film(model) -> Film | None:
    """
    A single film's twin (one with ``film = (eta1, eta2, eta3, kappa3)`` and ``thickness_d``) as the
    extension's parameters; None for any other material, or where the extension cannot hold the film.
    """
    film = getattr(model, "film", None)
    if film is None or not hasattr(model, "thickness_d"):
        return None
    eta1, eta2, eta3, kappa3 = (float(x) for x in film)
    d = float(model.thickness_d)
    if abs(eta1 - 1.0) > 1e-9 or eta2 < 1.0:
        return None  # the extension's film lies in air, and its index is at least 1
    if kappa3 > 0.0:  # a conductor: a metal whose base colour is its normal-incidence reflectance (grey)
        f0 = abs((complex(eta3, kappa3) - 1.0) / (complex(eta3, kappa3) + 1.0)) ** 2
        return Film(d, eta2, 1.0, 1.0, (f0, f0, f0))
    if eta3 < 1.0:
        return None  # KHR_materials_ior holds indices >= 1 only
    return Film(d, eta2, 1.0, 0.0, base_ior=eta3)


def _films_rgb(params: np.ndarray, metallic: bool, cos: np.ndarray) -> np.ndarray:
    """:func:`specular_reflectance` of many films at once: ``params`` ``(K, 6)`` (thickness, ior, factor, then
    the base colour for a metal) or ``(K, 4)`` (then the base's index for a dielectric) -> ``(K, len(cos), 3)``."""
    thickness, ior, factor = params[:, 0:1], params[:, 1:2], params[:, 2:3, None]
    f0 = params[:, None, 3:6] if metallic else np.repeat(_ior_to_f0(params[:, None, 3:4], 1.0), 3, axis=-1)
    plain = _schlick(f0, cos[None, :, None])
    iridescent = iridescent_fresnel(1.0, ior, f0, thickness, cos[None, :])
    return (1.0 - factor) * plain + factor * iridescent


def _lab(rgb: np.ndarray) -> np.ndarray:
    import colour

    return colour.XYZ_to_Lab(colorimetry.rgb_to_xyz(rgb), colour.XYZ_to_xy(colorimetry.white_xyz()))


def _films_delta_e(params: np.ndarray, metallic: bool, target_lab: np.ndarray, cos: np.ndarray) -> np.ndarray:
    """ΔE2000 ``(K, len(cos))`` of films ``params`` (:func:`_films_rgb`) against ``target_lab``."""
    import colour

    return np.asarray(colour.delta_E(_lab(_films_rgb(params, metallic, cos)), target_lab[None], method="CIE 2000"))


def _refine(start: np.ndarray, lower: np.ndarray, upper: np.ndarray, metallic: bool, target_lab, cos, loss: str = "linear"):
    """Bounded least squares on the ΔE2000 per angle from ``start`` (scipy), the Jacobian's differences in one batch."""
    from scipy.optimize import least_squares

    steps = np.array([0.05] + [1e-4] * 5)[: len(start)]

    def jacobian(p):
        sign = np.where(p + steps <= upper, 1.0, -1.0)
        batch = np.vstack([p, p + np.diag(steps * sign)])
        e = _films_delta_e(batch, metallic, target_lab, cos)
        return ((e[1:] - e[0]) / (steps * sign)[:, None]).T

    result = least_squares(lambda p: _films_delta_e(p[None], metallic, target_lab, cos)[0], np.clip(start, lower, upper),
                           jac=jacobian, bounds=(lower, upper), max_nfev=100, loss=loss)
    return result.x, result.cost


def _film_of(params: np.ndarray, metallic: bool, mapping: str, target: np.ndarray) -> Film:
    if metallic:
        film = Film(float(params[0]), float(params[1]), float(params[2]), 1.0, tuple(float(c) for c in params[3:6]), mapping=mapping)
    else:
        film = Film(float(params[0]), float(params[1]), float(params[2]), 0.0, base_ior=float(params[3]), mapping=mapping)
    film.delta_e = delta_e(film, target)
    return film


def fit_film(target: np.ndarray, starts: int = 3) -> Film:
    """
    The nearest metallic film to ``target`` (linear RGB at :data:`THETA_DEG`): a grid over thickness and
    index (factor 1, base colours from the target's normal-incidence colour and two greys) picks the
    ``starts``, then bounded least squares on the ΔE2000 per angle refines each (scipy); the best is kept.
    """
    cos = np.cos(np.radians(THETA_DEG))
    target = np.asarray(target, np.float64)
    target_lab = _lab(target)
    bases = [np.clip(target[0], 0.0, 1.0), np.full(3, 0.04), np.full(3, 0.5)]
    d, n = np.meshgrid(np.linspace(*THICKNESS_RANGE, 151), np.linspace(1.0, 2.6, 17), indexing="ij")
    grid = np.concatenate([np.column_stack([d.ravel(), n.ravel(), np.ones(d.size), np.broadcast_to(b, (d.size, 3))]) for b in bases])
    cost = np.sum(_films_delta_e(grid, True, target_lab, cos) ** 2, axis=1)
    # Also from no film at all (factor 0): a plain Schlick metal of the target's normal-incidence colour.
    plain = np.array([[THICKNESS_RANGE[1] / 3.0, 1.5, 0.0, *np.clip(target[0], 0.0, 1.0)]])
    grid, cost = np.vstack([plain, grid]), np.concatenate([[-1.0], cost])
    lower = np.array([THICKNESS_RANGE[0], IOR_RANGE[0], 0.0, 0.0, 0.0, 0.0])
    upper = np.array([THICKNESS_RANGE[1], IOR_RANGE[1], 1.0, 1.0, 1.0, 1.0])
    fits = [_refine(start, lower, upper, True, target_lab, cos) for start in grid[np.argsort(cost)[:starts]]]
    return _film_of(min(fits, key=lambda f: f[1])[0], True, "fit", target)


def _median_band(e: np.ndarray) -> np.ndarray:
    """The global fit's objective of ΔE2000 rows ``(K, n)``: :data:`MEDIAN_BAND`'s mean plus :data:`TAIL_WEIGHT` x the mean."""
    n = e.shape[1]
    middle = np.sort(e, axis=1)[:, int(round(MEDIAN_BAND[0] * n)):int(round(MEDIAN_BAND[1] * n))]
    return middle.mean(axis=1) + TAIL_WEIGHT * e.mean(axis=1)


def _from_opd(x: np.ndarray) -> np.ndarray:
    """Dielectric films ``(K, 4)`` as (``D_inc = 2 n d``, film index, factor, base index) -> :func:`_films_rgb`'s ``(K, 4)``."""
    return np.column_stack([x[:, 0] / (2.0 * x[:, 1]), x[:, 1:]])


def _dielectric_objective(x: np.ndarray, lab: np.ndarray, cos: np.ndarray, batch: int = 4096) -> np.ndarray:
    """:func:`_median_band` of dielectric films ``x`` (:func:`_from_opd`'s coordinates) against ``lab`` at ``cos``."""
    return np.concatenate([_median_band(_films_delta_e(_from_opd(x[i:i + batch]), False, lab, cos))
                           for i in range(0, len(x), batch)])


def search_dielectric(film: Film, dense_lab: np.ndarray, evolution: tuple[int, int] = EVOLUTION,
                      starts: int = POLISHED_STARTS) -> np.ndarray:
    """
    The dielectric film (:func:`_films_rgb`'s ``(4,)``) of least :func:`_median_band` against ``dense_lab`` (the
    material at :data:`DENSE_THETA_DEG`), from the direct mapping ``film``. Deterministic (a grid and a seeded
    search), in the coordinates the formula's colours follow: the optical path difference at normal incidence
    ``D_inc = 2 n d`` (its fringes), the film's index (their shift with angle, Snell in cos theta2, and the first
    interface), the factor and the base's index (the second interface; on either side of the film's it sets the
    phase, 0 or pi).

    1. A grid over ``D_inc`` from 0 to ``max(2 D, D + 1500)`` nm (``D`` the film's own) every :data:`GRID_OPD_STEP`
       nm, the film's index and its neighbours, the base's index and :data:`GRID_BASE_IORS`, and
       :data:`GRID_FACTORS`, on every fifth degree. The spec's Gaussian sensitivities fade at long paths faster
       than the CIE functions, so a thick film's best match is often a shorter, weaker one, far from its own.
    2. Differential evolution (scipy, seed 0) over the box, on every third degree, seeded with the grid's best.
    3. Nelder-Mead on every degree from the evolution's result and the grid's best ``starts`` distinct points.
    """
    from scipy.optimize import differential_evolution, minimize

    dense_cos = np.cos(np.radians(DENSE_THETA_DEG))
    d_own = 2.0 * film.ior * film.thickness
    d_top = max(2.0 * d_own, d_own + 1500.0)
    lower = np.array([0.0, IOR_RANGE[0], 0.0, IOR_RANGE[0]])
    upper = np.array([d_top, IOR_RANGE[1], 1.0, IOR_RANGE[1]])
    own = np.array([d_own, film.ior, film.factor, film.base_ior])
    film_iors = np.unique(np.clip(film.ior + np.asarray(GRID_FILM_IOR_OFFSETS), *IOR_RANGE))
    base_iors = np.unique(np.clip([film.base_ior, *GRID_BASE_IORS], *IOR_RANGE))
    grid = np.stack(np.meshgrid(np.arange(0.0, d_top + GRID_OPD_STEP, GRID_OPD_STEP), film_iors, GRID_FACTORS, base_iors,
                                indexing="ij"), axis=-1).reshape(-1, 4)
    grid = np.vstack([own, grid])
    cost = _dielectric_objective(grid, dense_lab[::5], dense_cos[::5])
    picked: list[np.ndarray] = []
    for k in np.argsort(cost, kind="stable"):  # the best points, each another fringe or another phase
        if all(abs(grid[k, 0] - p[0]) > 6.0 * GRID_OPD_STEP or (grid[k, 3] > grid[k, 1]) != (p[3] > p[1]) for p in picked):
            picked.append(grid[k])
        if len(picked) == starts:
            break
    popsize, generations = evolution
    evolved = differential_evolution(lambda x: _dielectric_objective(x.T, dense_lab[::3], dense_cos[::3]),
                                     list(zip(lower, upper)), x0=picked[0], vectorized=True, updating="deferred",
                                     popsize=popsize, maxiter=generations, tol=0.0, seed=0, polish=False)

    def dense(x):
        return float(_dielectric_objective(np.clip(x, lower, upper)[None], dense_lab, dense_cos)[0])

    scale = np.array([20.0, 0.05, 0.1, 0.1])  # the first simplex: a sixth of a fringe, and small index steps
    polished = []
    for x0 in [evolved.x, *picked]:
        simplex = np.vstack([x0, x0 + np.diag(scale)])
        result = minimize(dense, x0, method="Nelder-Mead",
                          options={"maxfev": 400, "xatol": 1e-3, "fatol": 1e-4, "initial_simplex": simplex})
        polished.append((result.fun, tuple(np.clip(result.x, lower, upper))))
    return _from_opd(np.array([min(polished)[1]]))[0]


def dense_delta_e(film: Film, dense_target: np.ndarray) -> np.ndarray:
    """ΔE2000 at :data:`DENSE_THETA_DEG` between the film's reflection and ``dense_target`` (``(90, 3)``)."""
    return colorimetry.delta_E_2000(specular_reflectance(film, np.cos(np.radians(DENSE_THETA_DEG))), dense_target)


def refine_film(film: Film, dense_target: np.ndarray) -> Film:
    """
    ``film`` (a direct mapping) with its thickness, film index, factor and base (the metal's colour, the
    dielectric's index: KHR_materials_ior) moved to lower the ΔE2000 to ``dense_target`` (the material at
    :data:`DENSE_THETA_DEG`).

    The spec's formula (Gaussian sensitivities, a matrix without white balance, unpolarised Schlick
    interfaces) cannot follow the polarised film at every angle with one set of parameters; least squares
    over all angles (plain and soft L1, from ``film``) lets the rim pull the centre, and stays near
    ``film``. For a dielectric base, a global search of the median over every degree
    (:func:`search_dielectric`) finds films that match the centre of the view closely and give way at the
    rim. Of ``film`` and the candidates, the one of least median ΔE2000 over :data:`DENSE_THETA_DEG` is kept;
    its ΔE is reported at :data:`THETA_DEG`. KHR_materials_specular is not written: engines differ in whether
    its colour reaches the film's second interface.
    """
    dense_target = np.asarray(dense_target, np.float64)
    target = dense_target[_REPORTED]
    metallic = film.metallic >= 0.5
    base = film.base_color if metallic else (film.base_ior,)
    start = np.array([film.thickness, film.ior, film.factor, *base])
    lower = np.array([THICKNESS_RANGE[0], IOR_RANGE[0], 0.0, *((0.0,) * 3 if metallic else (IOR_RANGE[0],))])
    upper = np.array([max(THICKNESS_RANGE[1], 2.0 * film.thickness), IOR_RANGE[1], 1.0,
                      *((1.0,) * 3 if metallic else (IOR_RANGE[1],))])
    film.delta_e = delta_e(film, target)
    candidates = [film]
    for loss in ("linear", "soft_l1"):
        params, _ = _refine(start, lower, upper, metallic, _lab(target), np.cos(np.radians(THETA_DEG)), loss)
        candidates.append(_film_of(params, metallic, "refined", target))
    if not metallic:
        candidates.append(_film_of(search_dielectric(film, _lab(dense_target)), False, "refined", target))

    def key(f: Film):
        e = dense_delta_e(f, dense_target)
        return float(np.median(e)), float(np.sum(e**2))

    return min(candidates, key=key)
