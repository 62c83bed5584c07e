"""
Multiple scattering in a layered Bragg structure, for the explorer's model: the light Eq. 34 leaves out,
put back as a reciprocal lobe the shader reads from one small RGB table (numpy only; the GLSL twin is
``compensated_brdf`` in ``shaders/lib/layered.glsl``).

Per wavelength the host computes the structure's directional albedo ``E(theta)`` with every bounce:

- each rough layer's albedos with multiple scattering among its facets
  (:func:`explorer.physics.multiscatter.layer_terms`: reflected once ``E_r``, crossed ballistically ``t_b``,
  and the rest ``m``, of which the share ``r`` goes up: the random walk's paths reweighted per wavelength);
- the light a layer reflects once and that leaves straight through the layers above and the coating
  (the visible-normal quadrature of Eq. 17 with each exit's transmissions, as Eq. 34 has it);
- everything else (light scattered among the facets, reflected back down by the layers above or inside the
  coating, total internal reflection included, or sent down) as diffuse fluxes between the interfaces,
  solved exactly with the layers' and the coating's hemispherical averages (the adding method);
- the base's bounces: ``rho_d T(i) T(o) / (pi n^2 (1 - rho_d R_under))`` with ``T`` all that reaches the base
  from the direction and ``R_under`` what the structure sends back to it (per RGB channel of ``rho_d``, as the
  position-free walk weighs the base's bounces: exact for every order).

The lobe the model adds to Eq. 34 (:func:`explorer.physics.layered.single_reflection_brdf`) is

    M(i) M(o) / (pi M_avg)  +  [rho_d T(i) T(o) / (1 - rho_d R_under) - rho_d a(i) a(o)] / (pi n^2),

``M = E_layers - E_Eq34`` the layers' missing albedo (clipped at 0: where single scattering is above the
model it is kept), ``M_avg = 2 int M cos sin``, ``a`` Eq. 34's own path to the base. Its directional albedo is
``M(theta)`` plus the base's missing part: the model's albedo is ``E`` at every angle and wavelength. It is
reciprocal (a sum of products ``g(i) g(o)``); its angular shape is Kulla & Conty's (2017). Summed over the
wavelengths against the CMFs it is one RGB table over ``(theta_i, theta_o)`` in air: the shader's only extra
work is one bilinear fetch (:func:`rgb_table`, :func:`lookup_rgb`); Mitsuba's spectral plugin evaluates it per
wavelength (:func:`lobe_spectrum`).

References
----------
Kulla, Conty (2017). Revisiting physically based shading at Imageworks. SIGGRAPH course. The lobe's form.
Heitz, Hanika, d'Eon, Dachsbacher (2016). Multiple-scattering microfacet BSDFs with the Smith model.
Fourneau, Pacanowski, Barla (2024). Computer Graphics Forum 43(2). Eqs. 17, 28, 34.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Sequence

import numpy as np
from numpy.typing import ArrayLike

from explorer.physics import colorimetry, layered, multiscatter
from explorer.physics.fresnel import fresnel_reflectance

#: Rows (and columns) of the lobe's table: theta in air = k * TABLE_STEP_DEG, k = 0..45.
TABLE_STEP_DEG = multiscatter.COMPENSATION_STEP_DEG
TABLE_ROWS = multiscatter.COMPENSATION_ROWS


@dataclass(frozen=True)
class StackCompensation:
    """
    What a structure's lobe is made of, per wavelength (471, the last axis), at ``theta = k 2 deg`` in air.

    Attributes
    ----------
    missing : ndarray, shape (TABLE_ROWS, 471)
        ``M``: the layers' albedo beyond Eq. 34's.
    missing_average : ndarray, shape (471,)
        ``M_avg``.
    through : ndarray, shape (TABLE_ROWS, 471)
        ``T``: the light that reaches the base (all bounces, the coating's transmission included).
    eq34_through : ndarray, shape (TABLE_ROWS, 471)
        ``a``: Eq. 34's path to the base (``1 - F`` times Eq. 28's transmissivities and the gaps).
    under : ndarray, shape (471,)
        ``R_under``: of diffuse light leaving the base, what the structure sends back to it.
    radiance_scale : float
        ``1 / n^2`` under a coating, else 1 (Eq. 34's).
    albedo : ndarray, shape (TABLE_ROWS, 471)
        ``E``: the layers' directional albedo with every bounce (the base black), for the studies.
    """

    missing: np.ndarray = field(repr=False)
    missing_average: np.ndarray = field(repr=False)
    through: np.ndarray = field(repr=False)
    eq34_through: np.ndarray = field(repr=False)
    under: np.ndarray = field(repr=False)
    radiance_scale: float = 1.0
    albedo: np.ndarray = field(repr=False, default=None)


def table_theta() -> np.ndarray:
    """The table's rows (radians, in air)."""
    return np.radians(np.arange(TABLE_ROWS) * TABLE_STEP_DEG)


def _diffuse_solve(R: np.ndarray, T: np.ndarray, F_in: float | np.ndarray, g: float) -> np.ndarray:
    """
    The inverse of the diffuse fluxes' system (per wavelength): unknowns ``U_0..U_L`` (up, leaving the bottom of
    gap j) and ``D_0..D_L`` (down, leaving its top); layer ``j`` (1..L) between gaps ``j - 1`` and ``j`` reflects
    ``R[j-1]`` and transmits ``T[j-1]`` (hemispherical averages, shape (L, 471)); the coating reflects ``F_in``
    back down; the base is black; each gap crossing keeps ``g``. Returns ``A^-1``, shape (471, 2(L+1), 2(L+1)).
    """
    L = R.shape[0]
    n = 2 * (L + 1)
    K = R.shape[1]
    A = np.broadcast_to(np.eye(n), (K, n, n)).copy()
    U = lambda j: j  # noqa: E731
    D = lambda j: L + 1 + j  # noqa: E731
    A[:, D(0), U(0)] -= np.broadcast_to(F_in, (K,)) * g
    for j in range(1, L + 1):
        A[:, U(j - 1), D(j - 1)] -= R[j - 1] * g
        A[:, U(j - 1), U(j)] -= T[j - 1] * g
        A[:, D(j), D(j - 1)] -= T[j - 1] * g
        A[:, D(j), U(j)] -= R[j - 1] * g
    return np.linalg.inv(A)


def stack_compensation(stack: layered.LayeredBragg, tables: Sequence[layered.LayerTables] | None = None,
                       terms: Sequence[multiscatter.LayerTerms] | None = None) -> StackCompensation:
    """
    The structure's :class:`StackCompensation` (see the module docstring), from its layer tables and each
    layer's :class:`explorer.physics.multiscatter.LayerTerms` (built when omitted).
    """
    tables = layered.stack_tables(stack) if tables is None else tuple(tables)
    terms = tuple(layer_terms_of(t) for t in tables) if terms is None else tuple(terms)
    L = len(tables)
    rows = multiscatter.compensation_theta()  # host angles
    cos_rows = np.cos(rows)
    n1, coating = stack.n1, stack.coating and stack.n1 != 1.0
    theta_table = tables[0].theta
    cos_table = np.cos(theta_table)
    step = theta_table[1] - theta_table[0]
    # The coating from inside (total internal reflection included) and each gap's crossing, per host angle.
    F_in_table = fresnel_reflectance(np.maximum(cos_table, 1e-9), n1, 1.0) if coating else np.zeros_like(cos_table)
    g_table = layered.gap_transmittance(stack.tau_h, cos_table)
    F_in_rows = fresnel_reflectance(np.maximum(cos_rows, 1e-9), n1, 1.0) if coating else np.zeros_like(cos_rows)
    g_rows = layered.gap_transmittance(stack.tau_h, cos_rows)
    avg = lambda x: multiscatter.hemispherical_average(x, rows)  # noqa: E731
    R_avg = np.stack([avg(t.reflected) for t in terms])
    T_avg = np.stack([avg(t.transmitted) for t in terms])
    F_avg = float(avg(F_in_rows[:, None])[0])
    g_avg = float(avg(g_rows[:, None])[0])
    inv = _diffuse_solve(R_avg, T_avg, F_avg, g_avg)
    escape = (1.0 - F_avg) * g_avg * inv[:, 0, :]  # per unit source, the part that leaves into air
    to_base = g_avg * inv[:, 2 * L + 1, :]  # and the part that reaches the base
    # Exit factors toward the air of a layer's once-reflected light (0.25-degree rows): ballistic ones (this
    # model) and Eq. 28's (Eq. 34's), each through the gaps and the layers above and the coating.
    exit_b = ((1.0 - F_in_table) * g_table)[:, None] * np.ones((1, colorimetry.WAVELENGTHS.size))
    exit_34 = exit_b.copy()
    host = np.zeros((TABLE_ROWS, colorimetry.WAVELENGTHS.size))  # E per host angle, the base black
    host_34 = np.zeros_like(host)
    arrive = g_rows[:, None] * np.ones((1, colorimetry.WAVELENGTHS.size))  # directional light at layer l
    arrive_34 = arrive.copy()
    base = np.zeros_like(host)
    for l, (table, term) in enumerate(zip(tables, terms)):
        (direct, _), (_, single) = multiscatter.reflection_albedos(table.reflectance, table.transmissivity, theta_table,
                                                                    table.layer.alpha, [exit_b, exit_34],
                                                                    table.transmittance)
        exit_avg = avg(multiscatter.rows_at(exit_b, rows, step))
        up_source, down_source = l, L + 1 + (l + 1)  # the gap above layer l (up), the gap below (down)
        host += arrive * (direct + term.reflection * (escape[:, up_source] - exit_avg)
                          + term.up * term.missing * escape[:, up_source]
                          + (1.0 - term.up) * term.missing * escape[:, down_source])
        base += arrive * ((term.reflection + term.up * term.missing) * to_base[:, up_source]
                          + (1.0 - term.up) * term.missing * to_base[:, down_source])
        host_34 += arrive_34 * single
        arrive = arrive * term.ballistic * g_rows[:, None]
        t28 = layered.lookup(table.transmissivity, rows).astype(np.float64)
        arrive_34 = arrive_34 * t28 * g_rows[:, None]
        exit_b = exit_b * multiscatter.rows_at(term.ballistic, theta_table, np.radians(TABLE_STEP_DEG)) * g_table[:, None]
        exit_34 = exit_34 * table.transmissivity * g_table[:, None]
    base += arrive
    # From the host's angles to the air's: theta' = asin(sin theta / n1), the coating's 1 - F on the way in.
    theta_air = table_theta()
    if coating:
        theta_host = np.arcsin(np.clip(np.sin(theta_air) / n1, 0.0, 1.0))
        enter = (1.0 - layered.coating_reflectance(np.cos(theta_air), n1))[:, None]
    else:
        theta_host, enter = theta_air, np.ones((TABLE_ROWS, 1))
    on_air = lambda x: enter * multiscatter.rows_at(x, theta_host, np.radians(TABLE_STEP_DEG))  # noqa: E731
    E, E34 = on_air(host), on_air(host_34)
    missing = np.maximum(E - E34, 0.0)
    weight = np.cos(theta_air) * np.sin(theta_air)
    average = 2.0 * np.trapezoid(missing * weight[:, None], theta_air, axis=0)
    return StackCompensation(
        missing=missing, missing_average=average, through=on_air(base), eq34_through=on_air(arrive_34),
        under=to_base[:, L],
        radiance_scale=1.0 / (n1 * n1) if (stack.coating and n1 != 1.0) else 1.0, albedo=E,
    )


def layer_terms_of(table: layered.LayerTables) -> multiscatter.LayerTerms:
    """A layer's :class:`explorer.physics.multiscatter.LayerTerms` from its tables (the lossless transmissivity
    recomputed for absorbing facets)."""
    lossless = None
    if table.transmittance is not None:
        filt = layered.transmission_filter_for(table.layer.alpha)
        lossless = filt.weights @ (1.0 - np.asarray(table.reflectance, dtype=np.float64))
    return multiscatter.layer_terms(table.reflectance, table.transmissivity, table.theta, table.layer.alpha, lossless,
                                    table.transmittance)


def _rgb_weights() -> np.ndarray:
    """``K``, shape (471, 3): linear sRGB of a spectrum ``S`` is ``S @ K`` (the CMFs' integral, then XYZ to RGB)."""
    return colorimetry.spectrum_to_rgb(np.eye(colorimetry.WAVELENGTHS.size))


def rgb_table(compensation: StackCompensation, rho_d: ArrayLike) -> np.ndarray:
    """
    The lobe in linear sRGB (1/sr) at ``(theta_i, theta_o) = (j, k) * 2 deg`` in air: shape
    (TABLE_ROWS, TABLE_ROWS, 3), float32. Each channel ``c`` weighs the base's bounces with its ``rho_d[c]``.
    """
    K = _rgb_weights()
    c = compensation
    lobe = np.einsum("il,jl,lc->ijc", c.missing / (np.pi * np.maximum(c.missing_average, 1e-12)), c.missing, K)
    rho = np.broadcast_to(np.asarray(rho_d, dtype=np.float64), (3,))
    bounces = rho[None, :] / (1.0 - rho[None, :] * c.under[:, None])  # (471, 3): sum_k rho^k R_under^(k-1)
    lobe += np.einsum("il,jl,lc->ijc", c.through, c.through, K * bounces) * (c.radiance_scale / np.pi)
    lobe -= np.einsum("il,jl,lc->ijc", c.eq34_through, c.eq34_through, K) * (rho * c.radiance_scale / np.pi)
    return (0.5 * (lobe + lobe.swapaxes(0, 1))).astype(np.float32)  # reciprocal to the last bit of the sums


def lookup_rgb(table: np.ndarray, theta_i: ArrayLike, theta_o: ArrayLike) -> np.ndarray:
    """Bilinear interpolation of :func:`rgb_table` at angles in air (radians), in float32 as the texture unit."""
    step = np.radians(TABLE_STEP_DEG)

    def row(theta):
        x = np.clip(np.asarray(theta, dtype=np.float64), 0.0, 0.5 * np.pi) / step
        k = np.minimum(np.floor(x).astype(np.intp), TABLE_ROWS - 2)
        return k, (x - k).astype(np.float32)[..., None]

    (ki, fi), (ko, fo) = row(theta_i), row(theta_o)
    low = table[ki, ko] * (1 - fo) + table[ki, ko + 1] * fo
    high = table[ki + 1, ko] * (1 - fo) + table[ki + 1, ko + 1] * fo
    return low * (1 - fi) + high * fi


def lobe_parts(compensation: StackCompensation, theta_i: ArrayLike, theta_o: ArrayLike) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """
    The lobe per wavelength at angles in air (radians), in parts (each ``theta.shape + (471,)``): the layers'
    ``M(i) M(o) / (pi M_avg)``, ``T(i) T(o)`` and Eq. 34's ``a(i) a(o)``; with the base's albedo ``rho`` the lobe is
    ``layers + (rho T T / (1 - rho R_under) - rho a a) / (pi n^2)`` (:func:`lobe_spectrum`).
    """
    c = compensation
    step = np.radians(TABLE_STEP_DEG)
    at = lambda x, theta: multiscatter.rows_at(x, np.clip(np.asarray(theta, dtype=np.float64), 0.0, 0.5 * np.pi), step)  # noqa: E731
    layers = at(c.missing, theta_i) * at(c.missing, theta_o) / (np.pi * np.maximum(c.missing_average, 1e-12))
    return layers, at(c.through, theta_i) * at(c.through, theta_o), at(c.eq34_through, theta_i) * at(c.eq34_through, theta_o)


def lobe_spectrum(compensation: StackCompensation, theta_i: ArrayLike, theta_o: ArrayLike, rho_d: ArrayLike) -> np.ndarray:
    """The lobe per wavelength at angles in air: ``rho_d`` a number or spectra broadcasting with ``theta.shape + (471,)``."""
    c = compensation
    layers, TT, aa = lobe_parts(c, theta_i, theta_o)
    rho = np.asarray(rho_d, dtype=np.float64)
    return layers + (TT * rho / (1.0 - rho * c.under) - rho * aa) * (c.radiance_scale / np.pi)


def air_angles(i: ArrayLike, o: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """The polar angles of ``i`` and ``o`` (unit vectors, ``n = +z``) by atan2, as the shader's ``polar_angle``."""
    i, o = np.asarray(i, dtype=np.float64), np.asarray(o, dtype=np.float64)
    ti = np.arctan2(np.linalg.norm(i[..., :2], axis=-1), np.maximum(i[..., 2], 0.0))
    to = np.arctan2(np.linalg.norm(o[..., :2], axis=-1), np.maximum(o[..., 2], 0.0))
    return ti, to


