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
  coating, total internal reflection included, or sent down) as fluxes between the interfaces in a few
  angular bins (:data:`TRANSFER_EDGES_DEG`), solved exactly per wavelength (the adding method with a small
  transfer matrix per layer, :func:`_transfer_solve`). A layer's matrix keeps the direction of what it reflects
  once (its own lobe, by the visible-normal quadrature of Eq. 17 with each bin as the exit) and of what it
  crosses ballistically, and spreads what it scatters among its facets as the random walk does
  (:func:`scattered_spread`). Treating that light as diffuse (one bin, hemispherical averages) put the
  two-layer stack's albedo 2 % low at alpha = 1 and 9 % high at alpha = 0.2 against the walk: a layer's
  once-reflected light stays in its lobe, and light scattered among pale facets leaves grazing;
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

import functools
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


#: The angular bins of the light between the interfaces (host angles, degrees: edges at odd degrees, between the
#: 2-degree rows): the light a layer sends to another keeps its direction to this resolution.
TRANSFER_EDGES_DEG = (0.0, 19.0, 35.0, 47.0, 57.0, 65.0, 73.0, 81.0, 90.0)


def transfer_bins(edges_deg: Sequence[float] = TRANSFER_EDGES_DEG) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """
    The bins over the rows of :func:`explorer.physics.multiscatter.compensation_theta`: each row's bin, its weight
    ``2 cos theta sin theta d theta`` (the trapezoid rule of the hemispherical average, so that the weights sum to
    about 1: the share of diffuse flux in the row), and each bin's share ``f_b`` (the weights' sum in it).
    """
    rows = multiscatter.compensation_theta()
    degrees = np.degrees(rows)
    index = np.clip(np.searchsorted(np.asarray(edges_deg), degrees, side="right") - 1, 0, len(edges_deg) - 2)
    width = np.full(rows.size, np.radians(TABLE_STEP_DEG))
    width[[0, -1]] *= 0.5
    weight = 2.0 * np.cos(rows) * np.sin(rows) * width
    return index, weight, np.bincount(index, weight, len(edges_deg) - 1)


#: The walk that spreads a layer's scattered light over the bins: paths per bin (incidence drawn within it,
#: as diffuse light in it), its seed; the facets reflect half the light, reweighted per wavelength (importance
#: reweighting: the walk with the layer's own facets, in expectation).
SPREAD_PATHS = 16000
SPREAD_SEED = 2017
#: The walk's facets reflect with this probability; any other reflectance reweighs the same paths.
SPREAD_SAMPLING_R = 0.5
#: The facet events kept per path (later ones are taken as the reweighting's mean, 1).
SPREAD_EVENTS = 10
#: The spread is reweighted every this many nm (a ratio: smoother than ``R``).
SPREAD_STEP_NM = 3


@functools.lru_cache(maxsize=8)
def spread_ensemble(alpha: float, edges_deg: tuple = TRANSFER_EDGES_DEG) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """
    The random walk's paths through a layer of roughness ``alpha`` (facets reflecting
    :data:`SPREAD_SAMPLING_R`), :data:`SPREAD_PATHS` per bin of ``edges_deg`` coming in
    with the flux of diffuse light in the bin (``sin^2 theta`` uniform in it), seeded: only those scattered among the
    facets (left upward after two reflections or more, or downward after one or more). Returns their events (rows of ``theta_d``, plus
    361 when reflected, 722 after the last), the bin they came in, the bin they left in, and whether they left upward.
    """
    from explorer.physics import microsurface

    rng = np.random.default_rng(SPREAD_SEED)
    edges = np.radians(np.asarray(edges_deg, dtype=np.float64))
    B = edges.size - 1
    n = SPREAD_PATHS * B
    come = np.repeat(np.arange(B), SPREAD_PATHS)
    low, high = np.sin(edges[come]) ** 2, np.sin(edges[come + 1]) ** 2
    sin2 = low + (high - low) * (np.arange(n) % SPREAD_PATHS + rng.random(n)) / SPREAD_PATHS  # stratified
    sin_t, cos_t = np.sqrt(sin2), np.sqrt(1.0 - sin2)
    count = np.zeros(n, dtype=np.int64)
    events = np.full((n, SPREAD_EVENTS), 722, dtype=np.int64)

    record = multiscatter.event_recorder(events, count)
    d = np.stack([-sin_t, 0.0 * sin_t, -cos_t], axis=-1)
    out, _, _, up, alive, _, reflections = microsurface.walk(
        d, np.ones((n, 1)), np.ones((n, 1)), float(alpha),
        lambda cos_d, rows: np.full((rows.size, 1), SPREAD_SAMPLING_R), rng, record=record)
    scattered = alive & (((reflections >= 2) & up) | ((reflections >= 1) & ~up))
    theta_out = np.arccos(np.clip(np.abs(out[:, 2]), 0.0, 1.0))
    leave = np.clip(np.searchsorted(edges, theta_out, side="right") - 1, 0, B - 1)
    return events[scattered], come[scattered], leave[scattered], up[scattered]


def scattered_spread(reflectance: ArrayLike, transmittance: ArrayLike | None, alpha: float,
                     edges_deg: Sequence[float] = TRANSFER_EDGES_DEG) -> tuple[np.ndarray, np.ndarray]:
    """
    How a layer's light scattered among its facets leaves, over the bins, per wavelength: ``(up, down)``, each
    shape (471, B out, B in), each column summing to 1: of the light coming in diffuse within a bin and scattered
    upward (downward), the part in each bin going out. From :func:`spread_ensemble` reweighted per wavelength by
    each event's ``R / R_s`` or ``T / (1 - R_s)`` (the walk with the layer's own facets, in expectation). The
    scattered light is not diffuse: with facets that reflect little it leaves grazing (3.6 times the diffuse
    share in the last bin, down, at ``R = 0.1``, ``alpha = 1``), with facets that reflect most near the normal.
    """
    edges_deg = tuple(float(e) for e in edges_deg)
    B = len(edges_deg) - 1
    W = np.shape(reflectance)[1]
    columns = np.unique(np.r_[np.arange(0, W, SPREAD_STEP_NM), W - 1])
    R = np.asarray(reflectance, dtype=np.float32)[:, columns]
    T = np.float32(1.0) - R if transmittance is None else np.asarray(transmittance, dtype=np.float32)[:, columns]
    Rs = SPREAD_SAMPLING_R
    factors = np.concatenate([T / np.float32(1.0 - Rs), R / np.float32(Rs), np.ones((1, R.shape[1]), np.float32)])
    events, come, leave, up = spread_ensemble(float(alpha), edges_deg)
    weight = factors[events[:, 0]]
    for j in range(1, events.shape[1]):
        going = np.flatnonzero(events[:, j] != 722)
        if going.size == 0:
            break
        weight[going] *= factors[events[going, j]]
    spreads = []
    for side in (up, ~up):
        at = np.flatnonzero(side)
        cell = come[at] * B + leave[at]
        sums = np.stack([np.bincount(cell, weight[at, c].astype(np.float64), B * B) for c in range(columns.size)])
        sums = sums.reshape(columns.size, B, B).transpose(0, 2, 1)  # (columns, out, in)
        total = sums.sum(axis=1, keepdims=True)
        _, _, share = transfer_bins(edges_deg)
        spread = np.where(total > 0.0, sums / np.maximum(total, 1e-300), share[None, :, None])
        wavelengths = np.arange(W)
        flat = spread.reshape(columns.size, -1)
        spreads.append(np.stack([np.interp(wavelengths, columns, flat[:, k]) for k in range(flat.shape[1])], axis=-1).reshape(W, B, B))
    return spreads[0], spreads[1]


def _bin_average(x: np.ndarray, index: np.ndarray, weight: np.ndarray, share: np.ndarray) -> np.ndarray:
    """Per bin, the flux-weighted mean of a per-row table ``x`` (rows, 471): shape (bins, 471)."""
    out = np.zeros((share.size, x.shape[1]))
    np.add.at(out, index, x * weight[:, None])
    return out / np.maximum(share, 1e-300)[:, None]


def _transfer_solve(R: np.ndarray, T: np.ndarray, F_in: np.ndarray, g: np.ndarray) -> np.ndarray:
    """
    The inverse of the fluxes' system between the interfaces (per wavelength), in angular bins: unknowns
    ``U_j[b]`` (up, leaving the bottom of gap ``j``, ``j = 0..L``) and ``D_j[b]`` (down, leaving its top); layer ``j``
    (1..L) between gaps ``j - 1`` and ``j`` sends ``R[j-1][:, b_out, b_in]`` of a bin's flux back and ``T[j-1]``
    through (shape (L, 471, B, B), the same from either side); the coating reflects ``F_in[b]`` back down (471, B);
    the base is black; each gap crossing keeps ``g[b]`` (B,). Returns ``A^-1``, shape (471, 2(L+1)B, 2(L+1)B), the
    unknowns ordered ``U_0..U_L, D_0..D_L``, each its ``B`` bins. With one bin it is the adding method's diffuse fluxes.
    """
    L, K, B = R.shape[0], R.shape[1], R.shape[2]
    n = 2 * (L + 1) * B
    A = np.broadcast_to(np.eye(n), (K, n, n)).copy()
    U = lambda j: slice(j * B, (j + 1) * B)  # noqa: E731
    D = lambda j: slice((L + 1 + j) * B, (L + 2 + j) * B)  # noqa: E731
    A[:, D(0), U(0)] -= np.eye(B)[None] * (F_in * g[None, :])[:, None, :]
    for j in range(1, L + 1):
        A[:, U(j - 1), D(j - 1)] -= R[j - 1] * g[None, None, :]
        A[:, U(j - 1), U(j)] -= T[j - 1] * g[None, None, :]
        A[:, D(j), D(j - 1)] -= T[j - 1] * g[None, None, :]
        A[:, D(j), U(j)] -= R[j - 1] * g[None, None, :]
    return np.linalg.inv(A)


def stack_compensation(stack: layered.LayeredBragg, tables: Sequence[layered.LayerTables] | None = None,
                       terms: Sequence[multiscatter.LayerTerms] | None = None,
                       edges_deg: Sequence[float] = TRANSFER_EDGES_DEG) -> StackCompensation:
    """
    The structure's :class:`StackCompensation` (see the module docstring), from its layer tables and each
    layer's :class:`explorer.physics.multiscatter.LayerTerms` (built when omitted). ``edges_deg``: the angular bins
    of the light between the interfaces (:data:`TRANSFER_EDGES_DEG`; ``(0, 90)`` treats it as diffuse).
    """
    tables = layered.stack_tables(stack) if tables is None else tuple(tables)
    terms = tuple(layer_terms_of(t) for t in tables) if terms is None else tuple(terms)
    L = len(tables)
    W = colorimetry.WAVELENGTHS.size
    rows = multiscatter.compensation_theta()  # host angles
    cos_rows = np.cos(rows)
    n1, coating = stack.n1, stack.coating and stack.n1 != 1.0
    theta_table = tables[0].theta
    cos_table = np.cos(theta_table)
    index, weight, share = transfer_bins(edges_deg)
    B = share.size
    binned = lambda x: _bin_average(np.broadcast_to(x, (rows.size, W)), index, weight, share)  # noqa: E731
    # The coating from inside (total internal reflection included) and each gap's crossing, per host angle.
    F_in_table = fresnel_reflectance(np.maximum(cos_table, 1e-9), n1, 1.0) if coating else np.zeros_like(cos_table)
    g_table = layered.gap_transmittance(stack.tau_h, cos_table)
    F_in_rows = fresnel_reflectance(np.maximum(cos_rows, 1e-9), n1, 1.0) if coating else np.zeros_like(cos_rows)
    g_rows = layered.gap_transmittance(stack.tau_h, cos_rows)
    F_bins = binned(F_in_rows[:, None])[:, 0]
    g_bins = binned(g_rows[:, None])[:, 0]
    # Each layer's transfer between the bins: reflected once into each bin (the visible-normal quadrature with
    # the bin as exit factor: its own lobe, not diffuse), scattered among the facets (up and down, spread as
    # diffuse light over the bins), crossed ballistically (its own bin). Per bin in, the mean over its rows.
    bin_of_table = np.clip(np.searchsorted(np.asarray(edges_deg), np.degrees(theta_table), side="right") - 1, 0, B - 1)
    indicators = [np.broadcast_to((bin_of_table == b).astype(np.float64)[:, None], (theta_table.size, W)) for b in range(B)]
    exit_b = ((1.0 - F_in_table) * g_table)[:, None] * np.ones((1, W))
    exit_34 = exit_b.copy()
    once, direct_exit, single_exit = [], [], []
    for table, term in zip(tables, terms):
        (direct, _, *into), (_, single, *_) = multiscatter.reflection_albedos(
            table.reflectance, table.transmissivity, theta_table, table.layer.alpha, [exit_b, exit_34] + indicators,
            table.transmittance)
        once.append(np.stack(into, axis=1))  # (rows, B out, 471): E_r into each bin
        direct_exit.append(direct)
        single_exit.append(single)
        exit_b = exit_b * multiscatter.rows_at(term.ballistic, theta_table, np.radians(TABLE_STEP_DEG)) * g_table[:, None]
        exit_34 = exit_34 * table.transmissivity * g_table[:, None]
    R_bins = np.zeros((L, W, B, B))
    T_bins = np.zeros((L, W, B, B))
    ballistic_bins = []
    spreads = []
    for l, (table, term) in enumerate(zip(tables, terms)):
        spread_up, spread_down = scattered_spread(table.reflectance, table.transmittance, table.layer.alpha, edges_deg)
        spreads.append((spread_up, spread_down))
        scattered_up, scattered_down = binned(term.up * term.missing), binned((1.0 - term.up) * term.missing)
        for b_out in range(B):
            R_bins[l, :, b_out, :] = binned(once[l][:, b_out, :]).T
        R_bins[l] += spread_up * scattered_up.T[:, None, :]
        T_bins[l] = spread_down * scattered_down.T[:, None, :]
        ballistic_bins.append(binned(term.ballistic))
        T_bins[l] += np.einsum("bk,bc->kbc", ballistic_bins[l], np.eye(B))
    inv = _transfer_solve(R_bins, T_bins, np.broadcast_to(F_bins, (W, B)), g_bins)
    U = lambda j: slice(j * B, (j + 1) * B)  # noqa: E731
    D = lambda j: slice((L + 1 + j) * B, (L + 2 + j) * B)  # noqa: E731
    # Per unit flux in each bin of each unknown (a source there): the part that leaves into air, and that reaches the base.
    escape = np.einsum("b,kbp->kp", (1.0 - F_bins) * g_bins, inv[:, U(0), :])
    to_base = np.einsum("b,kbp->kp", g_bins, inv[:, D(L), :])
    host = np.zeros((TABLE_ROWS, W))  # E per host angle, the base black
    host_34 = np.zeros_like(host)
    arrive = g_rows[:, None] * np.ones((1, W))  # directional light at layer l
    arrive_34 = arrive.copy()
    base = np.zeros_like(host)
    first = np.ones((W, B)) * ((1.0 - F_bins) * g_bins)[None, :]  # the ballistic way out from U_l, bin by bin
    for l, (table, term) in enumerate(zip(tables, terms)):
        up_esc, down_esc = escape[:, U(l)], escape[:, D(l + 1)]  # (471, B)
        up_base, down_base = to_base[:, U(l)], to_base[:, D(l + 1)]
        # Reflected once: its way out straight through the layers above is exact (``direct``); the rest goes
        # through the bins' transfer (the solve's escape less its own ballistic first pass).
        spread_up, spread_down = spreads[l]
        via = lambda spread, to: np.einsum("kob,ko->kb", spread, to)[:, index].T  # noqa: E731  per row: scattered, then its fate
        host += arrive * (direct_exit[l] + np.einsum("rbk,kb->rk", once[l], up_esc - first)
                          + term.up * term.missing * via(spread_up, up_esc)
                          + (1.0 - term.up) * term.missing * via(spread_down, down_esc))
        base += arrive * (np.einsum("rbk,kb->rk", once[l], up_base) + term.up * term.missing * via(spread_up, up_base)
                          + (1.0 - term.up) * term.missing * via(spread_down, down_base))
        host_34 += arrive_34 * single_exit[l]
        arrive = arrive * term.ballistic * g_rows[:, None]
        t28 = layered.lookup(table.transmissivity, rows).astype(np.float64)
        arrive_34 = arrive_34 * t28 * g_rows[:, None]
        first = first * ballistic_bins[l].T * g_bins[None, :]
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
    weight_air = np.cos(theta_air) * np.sin(theta_air)
    average = 2.0 * np.trapezoid(missing * weight_air[:, None], theta_air, axis=0)
    # Diffuse light leaving the base (spread over the bins as diffuse light): what comes back to it.
    under = np.sum(to_base[:, U(L)] * share, axis=1)
    return StackCompensation(
        missing=missing, missing_average=average, through=on_air(base), eq34_through=on_air(arrive_34),
        under=under,
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


