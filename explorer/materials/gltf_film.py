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
#: The largest specularColorFactor the dielectric's fit may write (the extension allows any >= 0; F0 is clamped to 1).
SPECULAR_COLOR_MAX = 4.0


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


def iridescent_fresnel(outside_ior, film_ior, base_f0, thickness, cos_theta, viewer_guard: bool = False) -> np.ndarray:
    """
    The extension's film Fresnel (linear Rec. 709, ``(..., 3)``) at ``cos_theta`` (broadcast with the
    scalars ``outside_ior``, ``film_ior``, ``thickness`` in nm and the RGB ``base_f0`` ``(..., 3)``).
    ``viewer_guard``: the base's F0 clamped to ``[0, 0.9999]`` before it becomes an index, as the Khronos sample
    viewer and three.js do, instead of the text's ``F0 + 0.0001`` (they differ where F0 is near 0).
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
    sqrt_f0 = np.sqrt(np.clip(base_f0, 0.0, 0.9999) if viewer_guard else base_f0 + 0.0001)
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
    specular_color: tuple[float, float, float] = (1.0, 1.0, 1.0)  # KHR_materials_specular's specularColorFactor
    mapping: str = "direct"  # "direct" (a thin film), "refined" (from the direct one) or "fit" (the nearest film)
    delta_e: np.ndarray = field(default_factory=lambda: np.zeros(0))  # ΔE2000 at THETA_DEG
    direct: "Film | None" = None  # a refined film's direct mapping


def specular_reflectance(film: Film, cos_theta, viewer_guard: bool = False) -> np.ndarray:
    """The glTF material's smooth reflection at ``cos_theta`` (``(..., 3)``), black base colour for a dielectric
    (``viewer_guard``: :func:`iridescent_fresnel`'s)."""
    cos = np.asarray(cos_theta, dtype=np.float64)
    if film.metallic >= 0.5:
        f0 = np.asarray(film.base_color, np.float64)
        plain = _schlick(f0, cos[..., None])  # conductor_fresnel
    else:
        # iridescent_dielectric_layer with KHR_materials_specular over a black base: F0 its colour times the
        # index's (specularFactor 1, where engines agree: the sample viewer passes this F0, unweighted, to
        # evalIridescence), Schlick's plain Fresnel and the film's second interface at that F0.
        f0 = np.minimum(_ior_to_f0(film.base_ior, 1.0) * np.asarray(film.specular_color, np.float64), 1.0)
        plain = _schlick(f0, cos[..., None])
    iridescent = iridescent_fresnel(1.0, film.ior, f0, film.thickness, cos, viewer_guard)
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


def _films_rgb(params: np.ndarray, metallic: bool, cos: np.ndarray, viewer_guard: bool = False) -> np.ndarray:
    """:func:`specular_reflectance` of many films at once: ``params`` ``(K, 6)`` (thickness, ior, factor, then
    the base colour for a metal) or ``(K, 7)`` (then the base's index and the specular colour for a dielectric,
    specularFactor 1) -> ``(K, len(cos), 3)``."""
    thickness, ior, factor = params[:, 0:1], params[:, 1:2], params[:, 2:3, None]
    if metallic:
        f0 = params[:, None, 3:6]
        plain = _schlick(f0, cos[None, :, None])
    else:
        f0 = np.minimum(_ior_to_f0(params[:, None, 3:4], 1.0) * params[:, None, 4:7], 1.0)
        plain = _schlick(f0, cos[None, :, None])
    iridescent = iridescent_fresnel(1.0, ior, f0, thickness, cos[None, :], viewer_guard)
    return (1.0 - factor) * plain + factor * iridescent


def _lab(rgb: np.ndarray) -> np.ndarray:
    import colour

    return colour.XYZ_to_Lab(colorimetry.rgb_to_xyz(rgb), colour.XYZ_to_xy(colorimetry.white_xyz()))


def _films_delta_e(params: np.ndarray, metallic: bool, target_lab: np.ndarray, cos: np.ndarray,
                   viewer_guard: bool = False) -> np.ndarray:
    """ΔE2000 ``(K, len(cos))`` of films ``params`` (:func:`_films_rgb`) against ``target_lab``."""
    import colour

    rgb = _films_rgb(params, metallic, cos, viewer_guard)
    return np.asarray(colour.delta_E(_lab(rgb), target_lab[None], method="CIE 2000"))


def _refine(start: np.ndarray, lower: np.ndarray, upper: np.ndarray, metallic: bool, target_lab, cos, loss: str = "linear"):
    """Bounded least squares on the ΔE2000 per angle from ``start`` (scipy), the Jacobian's differences in one batch."""
    from scipy.optimize import least_squares

    steps = np.array([0.05] + [1e-4] * 6)[: len(start)]

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
        film = Film(float(params[0]), float(params[1]), float(params[2]), 0.0, base_ior=float(params[3]), mapping=mapping,
                    specular_color=tuple(float(c) for c in params[4:7]))
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


#: The dielectric fit's last polish, Nelder-Mead on the median over every degree: its evaluations at most.
MEDIAN_POLISH_STEPS = 600
#: The per-channel base index range of the global fit's second search (F0 up to 0.51).
_BASE_INDEX_RANGE = (1.0, 6.0)
#: The global fit's differential evolutions: generations at most.
EVOLUTION_GENERATIONS = 120


def _from_base_indices(x: np.ndarray) -> np.ndarray:
    """Dielectric films ``(K, 6)`` (thickness, film index, factor, the base's index per channel) as
    :func:`_films_rgb`'s ``(K, 7)``: KHR_materials_ior at the top of :data:`IOR_RANGE`, its F0 coloured down."""
    f0 = _ior_to_f0(x[:, 3:6], 1.0) / _ior_to_f0(IOR_RANGE[1], 1.0)
    return np.column_stack([x[:, :3], np.full(len(x), IOR_RANGE[1]), f0])


#: The global search's seeds: a grid in the optical path difference at normal incidence (``D_inc = 2 n d``, nm;
#: its fringes) every :data:`SEED_OPD_STEP` nm, film indices (offsets from the film's own), base indices (on
#: either side of the film's: the second interface's phase, 0 or pi) and factors, white specular colour; its
#: :data:`SEEDS` best points, each another fringe or another phase, join both evolutions' first populations.
SEED_OPD_STEP = 20.0
SEED_FILM_IOR_OFFSETS = (-0.3, -0.15, 0.0, 0.15, 0.3)
SEED_BASE_IORS = (1.0, 1.5, 2.0, 2.5, 3.0)
SEED_FACTORS = (0.5, 0.75, 1.0)
SEEDS = 8


def _seeds(start: np.ndarray, lower: np.ndarray, upper: np.ndarray, lab: np.ndarray, cos: np.ndarray) -> np.ndarray:
    """The path-difference grid's best distinct dielectric films ``(SEEDS, 7)`` (:data:`SEED_OPD_STEP`) against
    ``lab`` at ``cos``, best first. The spec's Gaussian sensitivities fade at long paths faster than the CIE
    functions, so a thick film's best match is often a shorter, weaker one, far from its own."""
    d_own = 2.0 * start[1] * start[0]
    d_top = max(2.0 * d_own, d_own + 1500.0)
    film_iors = np.unique(np.clip(start[1] + np.asarray(SEED_FILM_IOR_OFFSETS), lower[1], upper[1]))
    base_iors = np.unique(np.clip([start[3], *SEED_BASE_IORS], lower[3], upper[3]))
    opd, n, factor, base = (a.ravel() for a in np.meshgrid(np.arange(0.0, d_top + SEED_OPD_STEP, SEED_OPD_STEP), film_iors,
                                                             SEED_FACTORS, base_iors, indexing="ij"))
    grid = np.column_stack([opd / (2.0 * n), n, factor, base, np.ones((len(n), 3))])
    grid = np.clip(np.vstack([start, grid]), lower, upper)
    cost = np.concatenate([_median_band(_films_delta_e(grid[i:i + 4096], False, lab, cos)) for i in range(0, len(grid), 4096)])
    picked: list[np.ndarray] = []
    for k in np.argsort(cost, kind="stable"):
        p = grid[k]
        if all(abs(2.0 * (p[0] * p[1] - q[0] * q[1])) > 6.0 * SEED_OPD_STEP or (p[3] > p[1]) != (q[3] > q[1]) for q in picked):
            picked.append(p)
        if len(picked) == SEEDS:
            break
    return np.array(picked)


def _global(start, lower, upper, dense_lab, dense_cos) -> list[np.ndarray]:
    """
    Dielectric films ``(7,)`` of low median ΔE2000: seeds from a path-difference grid (:func:`_seeds`), then
    differential evolution (scipy, seeded, so every run writes the same film) of :func:`_median_band` over the box
    from a first population of the seeds and a seeded Latin hypercube, and again with the base as an index per
    channel (the same films, searched in other coordinates: either alone misses some minima), on every second
    degree, then Nelder-Mead from the best of the two and the seeds on every degree. Returns that film and the
    :data:`TRIMMED_KEPT` best ends of the trimmed search (:func:`_trimmed_starts`), another way in.
    """
    from scipy.optimize import differential_evolution, minimize
    from scipy.stats import qmc

    coarse_lab, coarse_cos = dense_lab[::2], dense_cos[::2]
    seeds = _seeds(start, lower, upper, dense_lab[::5], dense_cos[::5])

    def search(decode, bounds, first, popsize):
        bounds = np.array(bounds, np.float64)
        fill = qmc.LatinHypercube(d=len(bounds), seed=0).random(popsize * len(bounds) - len(first))
        init = np.vstack([np.clip(first, bounds[:, 0], bounds[:, 1]), qmc.scale(fill, bounds[:, 0], bounds[:, 1])])
        result = differential_evolution(lambda x: _median_band(_films_delta_e(decode(x.T), False, coarse_lab, coarse_cos)),
                                        bounds, init=init, vectorized=True, updating="deferred",
                                        maxiter=EVOLUTION_GENERATIONS, tol=1e-8, seed=0, polish=False)
        return decode(result.x[None])[0]

    firsts = np.vstack([np.clip(start, lower, upper), seeds])
    found = [search(lambda x: x, list(zip(lower, upper)), firsts, 15)]
    index_bounds = [(lower[0], upper[0]), IOR_RANGE, (0.0, 1.0), *[_BASE_INDEX_RANGE] * 3]
    as_indices = np.column_stack([firsts[:, :3], np.repeat(firsts[:, 3:4], 3, axis=1)])
    found.append(search(_from_base_indices, index_bounds, as_indices, 20))

    def dense(p):
        return float(_median_band(_films_delta_e(np.clip(p, lower, upper)[None], False, dense_lab, dense_cos))[0])

    best = min([*found, *seeds], key=dense)
    polished = minimize(dense, best, method="Nelder-Mead", options={"maxfev": 1000, "xatol": 1e-4, "fatol": 1e-5})
    return [np.clip(polished.x, lower, upper), *_trimmed_starts(start, lower, upper, dense_lab, dense_cos)[:TRIMMED_KEPT]]


#: The trimmed search: a grid over the whole box in the path difference at normal incidence (``D_inc = 2 n d``,
#: every :data:`TRIMMED_OPD_STEP` nm up to :data:`TRIMMED_OPD_SPAN` x the film's own or 3000 nm), the film index
#: (1-3, every 0.1), two factors and three grey base F0; its :data:`TRIMMED_STARTS` best distinct points each
#: walk by Levenberg-Marquardt on the :data:`TRIMMED_KEEP` closest of the 90 angles (chosen again every
#: :data:`TRIMMED_RECHOOSE` steps), all starts in one batch.
TRIMMED_OPD_STEP = 20.0
TRIMMED_OPD_SPAN = 1.6
TRIMMED_FILM_IORS = np.arange(1.0, 3.0001, 0.1)
TRIMMED_FACTORS = (0.6, 1.0)
TRIMMED_F0 = (0.01, 0.05, 0.2)
TRIMMED_STARTS = 32
TRIMMED_KEEP = 50
TRIMMED_STEPS = 30
TRIMMED_RECHOOSE = 6
#: How many of the trimmed search's ends (best first) compete with the polished film on the median itself.
TRIMMED_KEPT = 3
#: The trimmed search's forward-difference steps in (D_inc nm, film index, factor, F0 per channel).
_TRIMMED_DIFF = np.array([0.5, 1e-4, 1e-4, 1e-5, 1e-5, 1e-5])


def _from_path_and_f0(x: np.ndarray, upper: np.ndarray) -> np.ndarray:
    """Dielectric films ``(K, 6)`` (``D_inc`` nm, film index, factor, the base's F0 per channel) as :func:`_films_rgb`'s
    ``(K, 7)``: KHR_materials_ior at the top of :data:`IOR_RANGE`, its F0 coloured down; thickness at most ``upper[0]``."""
    f0 = x[:, 3:6] / _ior_to_f0(IOR_RANGE[1], 1.0)
    return np.column_stack([np.minimum(x[:, 0] / (2.0 * x[:, 1]), upper[0]), x[:, 1:3], np.full(len(x), IOR_RANGE[1]), f0])


def _trimmed_starts(start, lower, upper, dense_lab, dense_cos) -> list[np.ndarray]:
    """
    Dielectric films ``(7,)``, the trimmed search's (:data:`TRIMMED_STARTS`) ends, best first. The median of the
    ΔE2000 over every degree is the largest of the closest half: least squares on the closest
    :data:`TRIMMED_KEEP` angles (a concentration step of least trimmed squares) pulls that half in, wherever on
    the sphere it lies, and from many starts at once it reaches fringes and indices far from the film's own.
    """
    box_lo = np.array([0.0, IOR_RANGE[0], 0.0, 0.0, 0.0, 0.0])
    f0_top = min(1.0, _ior_to_f0(IOR_RANGE[1], 1.0) * float(upper[4]))
    box_hi = np.array([max(3000.0, TRIMMED_OPD_SPAN * 2.0 * start[0] * start[1]), IOR_RANGE[1], 1.0, f0_top, f0_top, f0_top])

    def delta(x, lab=dense_lab, cos=dense_cos):
        return _films_delta_e(np.clip(_from_path_and_f0(x, upper), lower, upper), False, lab, cos)

    axes = (np.arange(0.0, box_hi[0] + TRIMMED_OPD_STEP, TRIMMED_OPD_STEP), TRIMMED_FILM_IORS, TRIMMED_FACTORS, TRIMMED_F0)
    grid = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 4)
    grid = np.column_stack([grid, grid[:, 3], grid[:, 3]])
    cost = np.concatenate([np.median(delta(grid[i:i + 8192], dense_lab[::5], dense_cos[::5]), axis=1)
                           for i in range(0, len(grid), 8192)])
    picked: list[np.ndarray] = []
    for k in np.argsort(cost, kind="stable"):
        p = grid[k]
        if all(abs(p[0] - q[0]) > 3.0 * TRIMMED_OPD_STEP or abs(p[1] - q[1]) > 0.25 for q in picked):
            picked.append(p)
        if len(picked) == TRIMMED_STARTS:
            break
    x = np.array(picked)
    count, size = x.shape
    damping = np.full(count, 1e-3)
    e = delta(x)
    for step in range(TRIMMED_STEPS):
        if step % TRIMMED_RECHOOSE == 0:
            keep = np.sort(np.argsort(e, axis=1, kind="stable")[:, :TRIMMED_KEEP], axis=1)
        r = np.take_along_axis(e, keep, axis=1)
        h = _TRIMMED_DIFF * np.where(x + _TRIMMED_DIFF <= box_hi, 1.0, -1.0)
        moved = (x[:, None, :] + np.eye(size)[None] * h[:, None, :]).reshape(-1, size)
        jac = (np.take_along_axis(delta(moved).reshape(count, size, -1), keep[:, None, :], axis=2) - r[:, None, :]) / h[:, :, None]
        normal = jac @ jac.transpose(0, 2, 1)
        diagonal = np.einsum("kii->ki", normal)
        shift = np.linalg.solve(normal + (damping[:, None] * (diagonal + 1e-9))[:, :, None] * np.eye(size)[None],
                                -np.einsum("kpn,kn->kp", jac, r)[..., None])[..., 0]
        trial = np.clip(x + shift, box_lo, box_hi)
        e_trial = delta(trial)
        better = np.sum(np.take_along_axis(e_trial, keep, axis=1) ** 2, axis=1) < np.sum(r**2, axis=1)
        x, e = np.where(better[:, None], trial, x), np.where(better[:, None], e_trial, e)
        damping = np.where(better, damping / 3.0, damping * 5.0)
    order = np.argsort(np.median(e, axis=1), kind="stable")
    return list(np.clip(_from_path_and_f0(x[order], upper), lower, upper))


def dense_delta_e(film: Film, dense_target: np.ndarray) -> np.ndarray:
    """ΔE2000 at :data:`DENSE_THETA_DEG` between the film's reflection and ``dense_target`` (``(90, 3)``)."""
    return colorimetry.delta_E_2000(specular_reflectance(film, np.cos(np.radians(DENSE_THETA_DEG))), dense_target)


def refine_film(film: Film, dense_target: np.ndarray) -> Film:
    """
    ``film`` (a direct mapping) with its thickness, film index, factor and base (the metal's colour; the
    dielectric's index, specular colour and factor: KHR_materials_specular) moved to lower the ΔE2000 to
    ``dense_target`` (the material at :data:`DENSE_THETA_DEG`).

    The spec's formula (Gaussian sensitivities, a matrix without white balance, unpolarised Schlick
    interfaces) cannot follow the polarised film at every angle with one set of parameters; least squares
    over all angles (plain and soft L1, from ``film``) lets the rim pull the centre, and stays near
    ``film``. A global search (:func:`_global`) of the median over every degree finds films that match
    half the angles closely and give way elsewhere, mostly at the rim. Of ``film`` and these, the one of least
    median ΔE2000 over :data:`DENSE_THETA_DEG` is kept, and (a dielectric) polished on that median by
    Nelder-Mead; its ΔE is reported at :data:`THETA_DEG`.
    """
    dense_target = np.asarray(dense_target, np.float64)
    target = dense_target[_REPORTED]
    metallic = film.metallic >= 0.5
    base = film.base_color if metallic else (film.base_ior, *film.specular_color)
    start = np.array([film.thickness, film.ior, film.factor, *base])
    lower = np.array([THICKNESS_RANGE[0], IOR_RANGE[0], 0.0, *((0.0,) * 3 if metallic else (1.0, 0.0, 0.0, 0.0))])
    upper = np.array([max(THICKNESS_RANGE[1], 2.0 * film.thickness), IOR_RANGE[1], 1.0,
                      *((1.0,) * 3 if metallic else (3.0, SPECULAR_COLOR_MAX, SPECULAR_COLOR_MAX, SPECULAR_COLOR_MAX))])
    film.delta_e = delta_e(film, target)
    dense_cos = np.cos(np.radians(DENSE_THETA_DEG))
    candidates = [film]
    for loss in ("linear", "soft_l1"):
        params, _ = _refine(start, lower, upper, metallic, _lab(target), np.cos(np.radians(THETA_DEG)), loss)
        candidates.append(_film_of(params, metallic, "refined", target))
    if not metallic:
        candidates += [_film_of(p, False, "refined", target) for p in _global(start, lower, upper, _lab(dense_target), dense_cos)]

    def key(f: Film):
        # The worse of the two readings of the base's F0 (the text's F0 + 0.0001, the sample viewer's clamp): a film
        # whose base index sits on the film's own (the phase's step) or whose F0 is near 0 reads differently.
        e = dense_delta_e(f, dense_target)
        viewer = colorimetry.delta_E_2000(specular_reflectance(f, dense_cos, viewer_guard=True), dense_target)
        return max(float(np.median(e)), float(np.median(viewer))), float(np.sum(e**2))

    best = min(candidates, key=key)
    if metallic:
        return best
    from scipy.optimize import minimize

    # Last, Nelder-Mead on the median itself (not its smooth band): a few hundredths, at the films nearest 1.
    lab = _lab(dense_target)
    x = np.array([best.thickness, best.ior, best.factor, best.base_ior, *best.specular_color])

    def worse_median(p):
        films = np.clip(p, lower, upper)[None]
        return max(float(np.median(_films_delta_e(films, False, lab, dense_cos, guard)[0])) for guard in (False, True))

    result = minimize(worse_median, x, method="Nelder-Mead", options={"maxfev": MEDIAN_POLISH_STEPS, "xatol": 1e-6, "fatol": 1e-7})
    return min([best, _film_of(np.clip(result.x, lower, upper), False, "refined", target)], key=key)
