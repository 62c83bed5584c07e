"""
The measurements of ``docs/validation.md`` that no user command makes, each as a Markdown table:

- ``host``: the Bragg mirror's methods under a host medium (Appendix D), water-like layers in air
  (n1 = 1.33, n2 = 1.8, nh = 1, N = 20) over the Figure 4 grid, against the converged reference;
- ``exactness``: Yeh's reflectance against the transfer-matrix package ``tmm``, the converged reference
  against a brute-force integral at 0.005 nm, the paper's 1-nm sum against the converged reference as N
  grows, and the tabulated method's table between its nodes;
- ``lobes``: the layered lobes (Bati et al. 2021) against ``tmm.inc_tmm``, forward(inverse(lobes)), the
  highest energies, the FGD table against a brute-force integral, the white furnace, GL against numpy,
  and timings.

``python -m explorer.dev.validation_studies host|exactness|lobes`` prints one (progress on stderr);
:mod:`explorer.dev.validation_doc` calls the same functions. Sizes are module constants (or arguments),
so that a test runs each on a tiny configuration. The references written here (``tmm``, the brute-force
integrals) are independent of the code they check, and the tests use them too.

References
----------
Fourneau, Pacanowski, Barla (2024). Interactive Exploration of Vivid Material Iridescence using Bragg
Mirrors. Computer Graphics Forum 43(2). Eq. 2 (Yeh), Figure 4, Appendix D.
Bati, Barla, Pacanowski (2021). An Inverse Method for the Exploration of Layered Material Appearance.
ACM TOG 40(4). Eqs. 2-6 (the lobes), Sec. 5.2 (highest energies), Algorithm 2.
"""

from __future__ import annotations

import argparse
import sys
import time
import warnings
from collections.abc import Callable, Sequence

import numpy as np

from explorer.bench import FIGURE4_DELTAS, FIGURE4_LAMBDAS, THETA_DEGREES
from explorer.bench.markdown_tables import markdown_table
from explorer.physics import bragg, colorimetry, inverse, lobes, microfacet
from explorer.physics.inverse import Lobe

Progress = Callable[[str], None] | None


def _say(progress: Progress, message: str) -> None:
    if progress is not None:
        progress(message)


def _dE(reference: np.ndarray, rgb: np.ndarray) -> tuple[float, float]:
    dE = colorimetry.delta_E_2000(reference, rgb)
    return float(np.median(dE)), float(np.max(dE))


def _pair(values: tuple[float, float]) -> str:
    return f"{values[0]:.2f} / {values[1]:.1f}" if values[1] >= 1 else f"{values[0]:.2f} / {values[1]:.2f}"


def relative_error(rgb: np.ndarray, reference: np.ndarray) -> np.ndarray:
    """Per row, ``max |rgb - reference|`` over channels relative to the reference's brightest channel."""
    return np.abs(rgb - reference).max(axis=-1) / np.abs(reference).max(axis=-1)


# --------------------------------------------------------------------------------------------------
# Under a host (Appendix D)

#: Water-like layers in air (Appendix D), N = 20; Λ and δ from the Figure 4 grid.
HOST_MIRROR = {"n1": 1.33, "n2": 1.8, "nh": 1.0, "N": 20}
HOST_S = 3


def host_rows(lambdas: Sequence[float] = FIGURE4_LAMBDAS, deltas: Sequence[float] = FIGURE4_DELTAS,
              theta_degrees: np.ndarray = THETA_DEGREES, s: int = HOST_S, progress: Progress = None) -> list[dict]:
    """Per mirror, median and max ΔE2000 of each method (basic, paper s, improved s, 1-nm sum) against the converged reference."""
    cos_theta = np.cos(np.radians(theta_degrees))
    rows = []
    for Lambda in lambdas:
        for delta in deltas:
            _say(progress, f"host: Lambda = {Lambda:g} nm, delta = {delta:g}")
            mirror = bragg.BraggMirror(HOST_MIRROR["n1"], HOST_MIRROR["n2"], Lambda, delta, HOST_MIRROR["N"], nh=HOST_MIRROR["nh"])
            reference = bragg.reference_rgb(cos_theta, mirror)
            methods = {
                "basic": bragg.approximate_rgb(cos_theta, mirror, 0),
                f"paper s = {s}": bragg.approximate_rgb(cos_theta, mirror, s),
                f"improved s = {s}": bragg.approximate_rgb(cos_theta, mirror, s, variant="improved"),
                "1-nm sum": bragg.reference_rgb(cos_theta, mirror, step=1.0),
            }
            rows.append({"Lambda": Lambda, "delta": delta, **{name: _dE(reference, rgb) for name, rgb in methods.items()}})
    return rows


def host_markdown(rows: list[dict], angles: int = THETA_DEGREES.size) -> str:
    """:func:`host_rows` as a table: one row per mirror, ``median / max`` per method."""
    names = [k for k in rows[0] if k not in ("Lambda", "delta")]
    body = [[f"{r['Lambda']:g}", f"{r['delta']:g}", *(_pair(r[n]) for n in names)] for r in rows]
    m = HOST_MIRROR
    return (f"n1 = {m['n1']:g}, n2 = {m['n2']:g}, nh = {m['nh']:g}, N = {m['N']}; median / max ΔE2000 over {angles} angles "
            "θ ∈ [0°, 89.5°] against the converged reference.\n\n" + markdown_table(["Λ (nm)", "δ", *names], body))


# --------------------------------------------------------------------------------------------------
# Exactness of the Bragg mirror


def tmm_mirror_reflectance(polarisation: str, mirror: bragg.BraggMirror, theta: float, wavelength: float) -> float:
    """``tmm.coh_tmm``'s reflectance of ``[nh] + [n2, n1] * N + [n1]`` (the mirror's first layer is n2)."""
    from tmm import coh_tmm

    indices = [mirror.eta_h] + [mirror.n2, mirror.n1] * mirror.N + [mirror.n1]
    thicknesses = [np.inf] + [mirror.d2, mirror.d1] * mirror.N + [np.inf]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        return coh_tmm(polarisation, indices, thicknesses, theta, wavelength)["R"]


#: Random mirrors per tmm comparison (each with and without a host), and their ranges.
TMM_MIRRORS = 200
TMM_SEED = 20240522


def tmm_agreement(count: int = TMM_MIRRORS, host: bool = False, seed: int = TMM_SEED) -> float:
    """Max |Yeh - tmm| over ``count`` random mirrors (N ≤ 40, θ ≤ 89°, both polarisations)."""
    rng = np.random.default_rng(seed + host)
    worst = 0.0
    for _ in range(count):
        mirror = bragg.BraggMirror(rng.uniform(1.0, 1.7), rng.uniform(1.0, 2.5), rng.uniform(100.0, 1000.0),
                                   rng.uniform(0.05, 0.95), int(rng.integers(1, 41)),
                                   nh=rng.uniform(1.0, 2.0) if host else None)
        theta, wavelength = np.radians(rng.uniform(0.0, 89.0)), rng.uniform(360.0, 830.0)
        for polarisation in ("s", "p"):
            ours = float(bragg.bragg_reflectance(np.cos(theta), wavelength, mirror, polarisation))
            worst = max(worst, abs(ours - tmm_mirror_reflectance(polarisation, mirror, theta, wavelength)))
    return worst


#: The brute-force integral's step (nm).
BRUTE_FORCE_STEP = 0.005


def brute_force_rgb(cos_theta: np.ndarray, mirror: bragg.BraggMirror, step: float = BRUTE_FORCE_STEP) -> np.ndarray:
    """The colour integral at a fixed fine step: trapezoids of R_λ (Eq. 2) times the linearly interpolated CMFs."""
    cmf = colorimetry.colour_matching_functions()
    nodes = np.arange(colorimetry.WAVELENGTH_MIN - 1, colorimetry.WAVELENGTH_MAX + 2, dtype=np.float64)
    padded = np.vstack([np.zeros(3), cmf, np.zeros(3)])
    wavelengths = np.linspace(nodes[0], nodes[-1], int(round((nodes[-1] - nodes[0]) / step)) + 1)
    xyz = np.zeros((cos_theta.size, 3))
    for chunk in np.array_split(np.arange(wavelengths.size), 8):
        lam = wavelengths[chunk[0] : chunk[-1] + 2]  # chunks overlap by one sample
        R = bragg.bragg_reflectance(cos_theta[:, None], lam, mirror)
        weights = np.stack([np.interp(lam, nodes, padded[:, c]) for c in range(3)], axis=-1)
        xyz += np.trapezoid(R[:, :, None] * weights[None], lam, axis=1)
    return colorimetry.xyz_to_rgb(xyz)


#: The converged reference against the brute-force integral: N, a few angles (grazing ones: the
#: resonances are narrowest there), the Figure 4 grid and two hosts (water-like layers in air; a denser host).
BRUTE_FORCE_N = (20, 100, 300)
BRUTE_FORCE_ANGLES = (0.0, 45.0, 70.0, 80.0, 88.0)
HOST_MIRRORS = ({"n1": 1.33, "n2": 1.8, "Lambda": 300.0, "delta": 0.5, "nh": 1.0},
                {"n1": 1.0, "n2": 1.5, "Lambda": 500.0, "delta": 0.5, "nh": 1.4})
#: The 1-nm sum and the converged reference's cost as N grows (Λ = 500 nm, δ = 0.5, 180 angles).
GROWING_N = (20, 100, 300, 1000)
#: The tabulated method's table between its nodes.
TABLE_N = (20, 100, 1000)


def exactness_rows(brute_force_n: Sequence[int] = BRUTE_FORCE_N, growing_n: Sequence[int] = GROWING_N,
                   table_n: Sequence[int] = TABLE_N, tmm_mirrors: int = TMM_MIRRORS,
                   grid: Sequence[tuple[float, float]] | None = None, theta_degrees: np.ndarray = THETA_DEGREES,
                   step: float = BRUTE_FORCE_STEP, progress: Progress = None) -> dict:
    """The four studies of :func:`exactness_markdown` (see the module docstring), as a JSON-able document."""
    grid = [(L, d) for L in FIGURE4_LAMBDAS for d in FIGURE4_DELTAS] if grid is None else grid
    _say(progress, f"exactness: Yeh against tmm, {tmm_mirrors} random mirrors twice")
    document = {"tmm": {"mirrors": tmm_mirrors, "no host": tmm_agreement(tmm_mirrors, False),
                        "host": tmm_agreement(tmm_mirrors, True)}}
    angles = np.cos(np.radians(BRUTE_FORCE_ANGLES))
    brute = []
    for N in brute_force_n:
        _say(progress, f"exactness: converged reference against a {step:g}-nm integral, N = {N}")
        mirrors = [bragg.BraggMirror(1.0, 1.5, L, d, N) for L, d in grid] + [bragg.BraggMirror(N=N, **h) for h in HOST_MIRRORS]
        error = max(relative_error(bragg.reference_rgb(angles, m), brute_force_rgb(angles, m, step)).max() for m in mirrors)
        brute.append({"N": N, "mirrors": len(mirrors), "max_relative": float(error)})
    document["brute_force"] = brute
    cos_theta = np.cos(np.radians(theta_degrees))
    growing = []
    for N in growing_n:
        _say(progress, f"exactness: the 1-nm sum against the converged reference, N = {N}")
        mirror = bragg.BraggMirror(1.0, 1.5, 500.0, 0.5, N)
        start = time.perf_counter()
        reference = bragg.reference_rgb(cos_theta, mirror)
        seconds = time.perf_counter() - start
        one_nm = bragg.reference_rgb(cos_theta, mirror, step=1.0)
        median, maximum = _dE(reference, one_nm)
        growing.append({"N": N, "max_relative": float(relative_error(one_nm, reference).max()), "dE_median": median,
                        "dE_max": maximum, "reference_s": seconds})
    document["one_nm"] = growing
    tables = []
    rng = np.random.default_rng(3)
    for N in table_n:
        _say(progress, f"exactness: the tabulated method's table between its nodes, N = {N}")
        mirror = bragg.BraggMirror(1.0, 1.5, 500.0, 0.5, N)
        table = bragg.tabulated_rgb_table.__wrapped__(mirror)
        spacing = 1.0 / (table.shape[0] - 1)
        midpoints = (np.arange(table.shape[0] - 1) + 0.5) * spacing
        # Every midpoint around Brewster's angle, where the colour turns fastest, and random ones.
        brewster = mirror.n2 / np.hypot(mirror.n1, mirror.n2)
        c = np.concatenate([rng.choice(midpoints, min(100, midpoints.size), replace=False),
                            midpoints[np.abs(midpoints - brewster) < 8 * spacing]])
        tables.append({"N": N, "entries": int(table.shape[0]),
                       "between": float(relative_error(bragg.tabulated_rgb(table, c), bragg.reference_rgb(c, mirror)).max())})
    document["table"] = tables
    return document


def exactness_markdown(document: dict) -> str:
    """:func:`exactness_rows` as four tables."""
    t = document["tmm"]
    out = [f"Yeh's reflectance (numpy) against `tmm.coh_tmm`, {t['mirrors']} random mirrors each (N ≤ 40, θ ≤ 89°, "
           "360-830 nm, s and p):", "",
           markdown_table(["host", "max |R − R_tmm|"], [["n1 (none)", f"{t['no host']:.1e}"], ["nh ∈ [1, 2]", f"{t['host']:.1e}"]]),
           "", f"The converged reference (`bragg.reference_rgb`) against an independent brute-force integral at "
           f"{BRUTE_FORCE_STEP:g} nm, at θ ∈ {{{', '.join(f'{a:g}' for a in BRUTE_FORCE_ANGLES)}}}° on the Figure 4 grid "
           "and two hosts; of the brightest linear RGB channel:", "",
           markdown_table(["N", "mirrors", "max relative error"],
                          [[str(r["N"]), str(r["mirrors"]), f"{r['max_relative']:.1e}"] for r in document["brute_force"]]),
           "", "The paper's 1-nm sum against the converged reference (Λ = 500 nm, δ = 0.5, 180 angles), and the "
           "converged reference's cost (numpy, float64):", "",
           markdown_table(["N", "max relative error", "ΔE2000 median / max", "converged reference"],
                          [[str(r["N"]), f"{r['max_relative']:.1e}", _pair((r["dE_median"], r["dE_max"])),
                            f"{r['reference_s']:.2f} s"] for r in document["one_nm"]]),
           "", "The tabulated method's table (method 3; Λ = 500 nm, δ = 0.5) against the converged reference between "
           "its nodes (every midpoint around Brewster's angle, where the colour turns fastest, and 100 random ones); "
           "of the brightest channel:", "",
           markdown_table(["N", "entries", "max relative error"],
                          [[str(r["N"]), str(r["entries"]), f"{r['between']:.1e}"] for r in document["table"]])]
    return "\n".join(out)


# --------------------------------------------------------------------------------------------------
# The layered lobes (Bati et al. 2021)


def tmm_incoherent_reflectance(etas, taus, theta: float, base_kappa: float = 0.0, wavelength: float = 500.0) -> float:
    """Unpolarised incoherent reflectance of media ``etas`` (optical depths ``taus`` between them) by ``tmm.inc_tmm``."""
    import tmm

    k = 1e-5  # a weakly absorbing layer of thickness d has tau = 4 pi k d / lambda; k too small to change Fresnel
    ns, ds = [etas[0]], [np.inf]
    for eta, tau in zip(etas[1:-1], taus):
        ns.append(eta + 1j * k)
        ds.append(tau * wavelength / (4 * np.pi * k))
    ns.append(etas[-1] + 1j * base_kappa)
    ds.append(np.inf)
    coherency = ["i"] * len(ns)
    return float(np.mean([tmm.inc_tmm(p, ns, ds, coherency, theta, wavelength)["R"] for p in "sp"]))


def brute_force_fgd(cos_theta: float, alpha: float, eta: float, kappa: float = 0.0, count: int = 400) -> np.ndarray:
    """∫ f_r cos θo dωo of the GGX BRDF with Fresnel F_{s,p}(i·h) on a (θo, φo) grid: ``(2,)`` for s and p."""
    theta = (np.arange(count) + 0.5) / count * np.pi / 2
    phi = (np.arange(2 * count) + 0.5) / (2 * count) * 2 * np.pi
    t, p = np.meshgrid(theta, phi, indexing="ij")
    o = np.stack([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)], axis=-1)
    i = np.array([np.sqrt(1 - cos_theta**2), 0.0, cos_theta])
    lobe, cos_d, _ = microfacet.microfacet_lobe(i, o, np.array([0.0, 0.0, 1.0]), alpha)
    F = lobes.fresnel_sp(cos_d, eta, kappa)
    d_omega = np.sin(t) * (np.pi / 2 / count) * (2 * np.pi / (2 * count))
    return (F * (lobe * o[..., 2] * d_omega)).sum(axis=(-1, -2))


#: Lobes of the paper's figures (Figs. 5, 10, 14-20) for forward(inverse(lobes)).
INVERSE_CASES = {
    "fig5a_dielectric": [Lobe(0.04, 0.0)],
    "rough_dielectric": [Lobe(0.2, 0.02)],
    "fig14a_conductor": [Lobe([0.9, 0.7, 0.5], 0.03, base="conductor")],
    "fig14a_coated_conductor": [Lobe(0.04, 0.0), Lobe([0.9, 0.7, 0.5], 0.03, base="conductor")],
    "fig10a_two_layer_smooth": [Lobe(0.15, 0.0, layers=2)],
    "fig10c_two_layer_rough": [Lobe(0.15, 0.02, layers=2)],
    "fig14b_two_layer_coloured": [Lobe([0.1, 0.2, 0.1], 0.03, layers=2)],
    "fig14b_coated": [Lobe(0.04, 0.0), Lobe([0.1, 0.2, 0.1], 0.03, layers=2)],
    "fig15b_two_layer_coloured": [Lobe([0.09, 0.09, 0.15], 0.0, layers=2)],
    "fig16_two_layer_conductor": [Lobe(0.45, 0.03, layers=2, base="conductor")],
    "fig19b_haze": [Lobe(0.1, 0.0), Lobe([0.35, 0.25, 0.3], 0.04, base="conductor")],
    "fig20_haze_colour": [Lobe([0.09, 0.14, 0.09], 0.005, layers=2), Lobe(0.09, 0.1)],
    "three_lobes": [Lobe(0.05, 0.0), Lobe(0.06, 0.03), Lobe(0.08, 0.1)],
}


def brightest_channel_below(stack: lobes.Stack, lobe_list: Sequence[Lobe], k: int) -> int:
    """The channel that set lobe k's roughness: the largest R' under the layers above (Eq. 18, Sec. 5.2.3)."""
    above = sum(lobe.layers for lobe in lobe_list[:k])
    if above == 0:
        return int(np.argmax(lobe_list[k].energy))
    statistics = lobes.stack_statistics(stack, above)
    R_prime = 1.0 / (statistics.T_0n * statistics.T_n0 / lobe_list[k].energy + statistics.R_n0)
    return int(np.argmax(R_prime))


def round_trip(cases: dict[str, list[Lobe]] = INVERSE_CASES) -> dict:
    """forward(inverse(lobes)) at normal incidence: worst energy error, variance error (setting channel, others), mean inversion time."""
    energy = variance = other = 0.0
    seconds = []
    for lobe_list in cases.values():
        start = time.perf_counter()
        stack = inverse.invert_lobes(lobe_list)
        seconds.append(time.perf_counter() - start)
        energies, variances = inverse.forward_lobes(stack, [lobe.layers for lobe in lobe_list])
        for k, lobe in enumerate(lobe_list):
            energy = max(energy, float(np.abs(energies[k] - lobe.energy).max()))
            c = brightest_channel_below(stack, lobe_list, k)
            variance = max(variance, abs(float(variances[k][c]) - lobe.variance))
            other = max(other, float(np.abs(variances[k] - lobe.variance).max()))
    return {"cases": len(cases), "energy": energy, "variance": variance, "other_channels": other,
            "inversion_ms": 1e3 * float(np.mean(seconds))}


def random_smooth_stack(rng: np.random.Generator):
    """A smooth stack of 1-4 interfaces with absorbing media, sometimes on a conductor base: (stack, etas, taus, kappa)."""
    count = int(rng.integers(1, 5))
    etas = [1.0] + list(rng.uniform(1.0, 2.5, count))
    taus = list(rng.uniform(0.0, 1.0, count - 1))
    kappa = float(rng.uniform(0.5, 4.0)) if rng.random() < 0.4 else 0.0
    if kappa:
        etas[-1] = float(rng.uniform(0.1, 1.5))
    stack = lobes.make_stack(etas[1:], [0.0] * count, tau=taus, base_kappa=kappa if kappa else None)
    return stack, etas, taus, kappa


#: The furnace's stacks (layered_lobes.brd values): the brightest is a bare conductor at α = 0.2.
FURNACE_STACKS = (
    {"layers": 3, "eta_1": 1.5, "eta_2": 4.0, "eta_3": 1.0, "alpha_1": 0.3, "alpha_2": 0.6, "alpha_3": 0.9},
    {"layers": 2, "conductor": 1, "eta_base": "0.05", "kappa_base": "6", "alpha_1": 0.4, "alpha_2": 0.8},
    {"layers": 2, "conductor": 1, "eta_base": "0.05", "kappa_base": "6", "alpha_1": 1.0, "alpha_2": 1.0},
    {"layers": 1, "conductor": 1, "eta_base": "0.05", "kappa_base": "6", "alpha_1": 0.2},
)
#: GL against numpy: the stacks (layered_lobes.brd values), views and image size.
GL_STACKS = {
    "two_dielectric": {},
    "coated_conductor": {"conductor": 1, "tau_1": "0.2,0.5,1.0", "alpha_1": 0.02, "alpha_2": 0.25},
    "three_tir": {"layers": 3, "eta_1": 2.5, "eta_2": 1.0, "eta_3": 1.5, "tau_2": "0.3,0.1,0", "alpha_3": 0.6, "tir": 1},
}
GL_VIEWS = ("lit", "slice", "scatter", "gradient")
#: The BRDF views' lights in the comparison (as tests/twins.py): off the x axis, so that φ matters.
GL_LIGHTS = {"lit": (30.0, 120.0), "scatter": (50.0, 200.0)}
#: Below this a pixel's error is taken against the floor (tests/twins.py's FLOOR).
GL_FLOOR = 1e-3


def hemisphere(count: int):
    """Midpoint directions over the upper hemisphere (θ × φ grid) and their solid angles."""
    theta = (np.arange(count) + 0.5) / count * np.pi / 2
    phi = (np.arange(2 * count) + 0.5) / (2 * count) * 2 * np.pi
    t, p = np.meshgrid(theta, phi, indexing="ij")
    o = np.stack([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)], axis=-1).reshape(-1, 3)
    return o, (np.sin(t) * (np.pi / 2 / count) * (np.pi / count)).ravel()


def lobes_rows(tmm_stacks: int = 20, fgd_samples: int = 150, fgd_count: int = 400, furnace_count: int = 96,
               gl_size: tuple[int, int] = (36, 28), lit_size: int = 256, repeats: int = 5, two_layer_samples: int = 31,
               seed: int = 0, progress: Progress = None, renderer=None) -> dict:
    """
    Every check of :func:`lobes_markdown`, as a JSON-able document (GL parts need an EGL context). ``renderer``: the
    :class:`explorer.gpu.Renderer` of the GL parts (default a new one, on a new context).
    """
    from explorer.materials.brd import load_material
    from explorer.materials.lobes_model import LayeredLobesModel
    from explorer.materials.models import model_for
    from explorer.materials.twins import shipped_file
    from explorer.physics import lobes_fgd

    rng = np.random.default_rng(seed)
    document: dict = {}
    _say(progress, f"lobes: {tmm_stacks} smooth stacks against tmm.inc_tmm")
    thetas = np.radians(np.linspace(0.0, 89.0, 46))
    worst = {"dielectric": [0, 0.0, 0.0], "conductor": [0, 0.0, 0.0]}  # per base: stacks, max error, its angle
    for _ in range(tmm_stacks):
        stack, etas, taus, kappa = random_smooth_stack(rng)
        ours = lobes.reflectance(stack, np.cos(thetas))
        reference = np.array([tmm_incoherent_reflectance(etas, taus, t, kappa) for t in thetas])
        error = np.abs(ours - reference[:, None]).max(axis=-1)
        entry = worst["conductor" if kappa else "dielectric"]
        entry[0] += 1
        if error.max() > entry[1]:
            entry[1:] = [float(error.max()), float(np.degrees(thetas[error.argmax()]))]
    document["tmm"] = {base: {"stacks": n, "max_abs": e, "theta": t} for base, (n, e, t) in worst.items()}
    _say(progress, f"lobes: forward(inverse(lobes)) on {len(INVERSE_CASES)} configurations")
    document["round_trip"] = round_trip()
    _say(progress, "lobes: the highest 1- and 2-layer dielectric energies")
    lo, hi = 0.3, 0.6  # bisection on the 2-layer class's validity at zero variance (Sec. 5.2.1)
    for _ in range(6):
        middle = 0.5 * (lo + hi)
        lo, hi = (middle, hi) if inverse.two_layer_class(middle, 0.0, samples=two_layer_samples).valid.any() else (lo, middle)
    document["highest"] = {"one_layer": float(lobes_fgd.normal_reflectance(1.0, lobes.ETA_MAX)), "two_layer": (lo, hi)}
    _say(progress, f"lobes: the FGD table against a brute-force integral, {fgd_samples} random (θ, α, η)")
    errors = []
    for _ in range(fgd_samples):
        cos_theta, alpha, eta = rng.uniform(0.05, 1.0), rng.uniform(0.05, 1.0), rng.uniform(1.05, 3.0)
        ours = float(lobes.fgd_dielectric(cos_theta, alpha, eta).mean(axis=0))
        errors.append(abs(ours - float(brute_force_fgd(cos_theta, alpha, eta, count=fgd_count).mean(axis=0))))
    document["fgd"] = {"samples": fgd_samples, "median": float(np.median(errors)), "p95": float(np.percentile(errors, 95))}
    _say(progress, f"lobes: white furnace, {len(FURNACE_STACKS)} stacks")
    material = load_material(shipped_file(LayeredLobesModel))
    o, d_omega = hemisphere(furnace_count)
    albedo = 0.0
    for overrides in FURNACE_STACKS:
        model = model_for(material, material.resolve(overrides))
        for cos_theta in (1.0, 0.7, 0.3, 0.05):
            L = np.array([np.sqrt(1 - cos_theta**2), 0.0, cos_theta])
            brdf = model.brdf(L, o, np.array([0.0, 0.0, 1.0]), None, None)
            albedo = max(albedo, float((brdf * (o[:, 2] * d_omega)[:, None]).sum(axis=0).max()))
    document["furnace"] = {"stacks": len(FURNACE_STACKS), "max_albedo": albedo}
    document.update(_lobes_gl(material, gl_size, lit_size, repeats, progress, renderer))
    return document


def _lobes_gl(material, gl_size, lit_size: int, repeats: int, progress: Progress, renderer=None) -> dict:
    from explorer.gpu import Renderer
    from explorer.materials.brd import load_material
    from explorer.materials.models import GGXSchlickModel, model_for
    from explorer.materials.twins import shipped_file
    from explorer.views.geometry import rim_distance
    from explorer.views.render import render_numpy

    renderer = Renderer() if renderer is None else renderer
    width, height = gl_size
    _say(progress, f"lobes: GL against numpy, {len(GL_STACKS)} stacks x {len(GL_VIEWS)} views")
    worst = 0.0
    for overrides in GL_STACKS.values():
        values = material.resolve(overrides)
        for view in GL_VIEWS:
            light = GL_LIGHTS.get(view)
            gl = renderer.render(material, values, view, width, height, light=light).astype(np.float64)
            reference = render_numpy(model_for(material, values), view, width, height, light=light)
            compared = rim_distance(view, width, height) > 1e-4  # the disc's float32 rim decides inside/outside
            scale = np.maximum(np.abs(reference).max(axis=-1), GL_FLOOR)
            worst = max(worst, float((np.abs(gl - reference).max(axis=-1) / scale)[compared].max()))
    _say(progress, f"lobes: a {lit_size}² lit frame, 1-4 interfaces and GGX + Schlick, {repeats} repeats")
    cases = [("GGX + Schlick", load_material(shipped_file(GGXSchlickModel)), {})]
    cases += [(f"{n} interface{'s' * (n > 1)}", material, {"layers": n}) for n in (1, 2, 3, 4)]
    resolved = [(name, m, m.resolve(o)) for name, m, o in cases]
    for _, m, values in resolved:  # compile and warm every program first
        renderer.time_frame(m, values, "lit", 16, 16)
    times: dict[str, list[float]] = {name: [] for name, _, _ in resolved}
    for _ in range(repeats):
        for name, m, values in resolved:
            times[name].append(renderer.time_frame(m, values, "lit", lit_size, lit_size))
    return {"gl": {"stacks": len(GL_STACKS), "views": list(GL_VIEWS), "size": list(gl_size), "max_relative": worst},
            "lit_ms": {name: float(np.median(t)) for name, t in times.items()}, "lit_size": lit_size, "device":
            renderer.ctx.info.get("GL_RENDERER", "unknown")}


def lobes_markdown(document: dict) -> str:
    """:func:`lobes_rows` as one table of checks."""
    t, r, h, f = document["tmm"], document["round_trip"], document["highest"], document["fgd"]
    g, size = document["gl"], document["lit_size"]
    lit = document["lit_ms"]
    rows = [
        *([f"smooth stacks on a {base} base (1–4 interfaces, absorbing media) against `tmm.inc_tmm`, θ ∈ [0°, 89°]",
           f"max {e['max_abs']:.1e} at θ = {e['theta']:g}° ({e['stacks']} random stacks; bound 1e-3)"] for base, e in t.items()),
        [f"forward(inverse(lobes)) at normal incidence, {r['cases']} configurations of Figures 5–20",
         f"energy ≤ {r['energy']:.1e}; variance ≤ {r['variance']:.1e} on the channel that sets the roughness, "
         f"≤ {r['other_channels']:.1e} on the others (Sec. 5.2.3)"],
        ["highest 1- / 2-layer dielectric energy (η ≤ 4; paper: 0.36 / 0.53)",
         f"{h['one_layer']:.2f} / between {h['two_layer'][0]:.3f} and {h['two_layer'][1]:.3f}"],
        [f"FGD table against a brute-force integral, {f['samples']} random (θ, α, η > 1)",
         f"median {f['median']:.1e}, 95th percentile {f['p95']:.1e}"],
        [f"white furnace ({document['furnace']['stacks']} stacks, α from 0.2 to 1, θ up to 87°)",
         f"albedo ≤ {document['furnace']['max_albedo']:.2f} (bound 1)"],
        [f"GL against the numpy twin, {' / '.join(g['views'])}, {g['stacks']} stacks, {g['size'][0]}×{g['size'][1]}",
         f"≤ {g['max_relative']:.1e} of a pixel's largest channel (bound 2e-3)"],
        [f"a {size}² `lit` frame on {document['device']} (GGX + Schlick: {lit['GGX + Schlick']:.1f} ms)",
         " / ".join(f"{v:.1f}" for k, v in lit.items() if k != "GGX + Schlick") + " ms for 1 / 2 / 3 / 4 interfaces"],
        [f"one inversion (numpy), mean of the {r['cases']} configurations", f"{r['inversion_ms']:.0f} ms (the paper: < 50 ms for Figure 17)"],
    ]
    return markdown_table(["check", "result"], rows)


# --------------------------------------------------------------------------------------------------
# The command


def _print_progress(message: str) -> None:
    print(message, file=sys.stderr, flush=True)


#: name -> (the Markdown of a full measurement, given a progress callback).
STUDIES: dict[str, Callable[[Progress], str]] = {
    "host": lambda progress: host_markdown(host_rows(progress=progress)),
    "exactness": lambda progress: exactness_markdown(exactness_rows(progress=progress)),
    "lobes": lambda progress: lobes_markdown(lobes_rows(progress=progress)),
}


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m explorer.dev.validation_studies", description=__doc__.split("\n\n")[0])
    parser.add_argument("study", choices=list(STUDIES), help="which table to measure and print as Markdown")
    arguments = parser.parse_args(argv)
    print(STUDIES[arguments.study](_print_progress))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
