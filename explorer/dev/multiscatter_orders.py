"""
Where the multiple-scattering model's error comes from, one layer at a time and per wavelength: the
microsurface random walk (:func:`explorer.physics.microsurface.walk`, each path on one wavelength, so that
each estimate is a plain Bernoulli mean) split by scattering order, against the model's terms
(:mod:`explorer.physics.multiscatter`) and Eq. 17 / Eq. 28 (single scattering), in the host medium.

Per preset layer, ``alpha``, incidence ``theta`` and wavelength:

- ``walk_up1``: reflected once, then left upward (crossing any occluders on its way out);
  Eq. 17 (``G1(i) G1(o)``, :func:`eq17_albedo`) and the model's ``E_r`` (``G_eff``) are its models;
- ``walk_up2``: reflected twice or more and left upward; the model's ``r m``;
- ``walk_down0``: crossed without reflecting; Eq. 28 (``(1 - rho) G1``) and the model's ``(1 - rho) G_eff^2``;
- ``walk_down1``: reflected at least once and left downward; the model's ``(1 - r) m``.

Run (a minute or two on 2 cores)::

    python3 -m explorer.dev.multiscatter_orders [--presets ...] [--alphas ...] [--paths 4000] [--write]

``--structure``: whole structures instead (:func:`structure_rows`, about two minutes). ``--write`` replaces the table of ``docs/layered_validation.md``. Every term is a mean over the studied
wavelengths; the walk's standard error per wavelength is at most ``0.5 / sqrt(paths)``, that of a mean
over the 11 wavelengths about a third of it.
"""

from __future__ import annotations

import argparse

import numpy as np

from explorer.physics import microfacet, microsurface, multiscatter, multiscatter_stack

THETA = (0.0, 20.0, 40.0, 55.0, 70.0)
#: Wavelength columns studied (of 471, 360-830 nm): every 30 nm from 400 to 700.
COLUMNS = tuple(range(40, 341, 30))
PRESETS = ("figure1_left_alpha04", "figure1_right_alpha04", "figure7_A")


def _lookup(table: np.ndarray, cos_theta: np.ndarray, column: np.ndarray) -> np.ndarray:
    """A layer table (rows every 0.25 deg) at ``acos(cos_theta)``, linearly, in the columns ``column``: shape (n, 1)."""
    theta = np.arccos(np.clip(cos_theta, 0.0, 1.0))
    x = theta / microfacet.THETA_STEP
    k = np.minimum(np.floor(x).astype(np.int64), table.shape[0] - 2)
    f = x - k
    return (table[k, column] * (1.0 - f) + table[k + 1, column] * f)[:, None]


def walk_orders(reflectance: np.ndarray, alpha: float, theta_deg: float, columns, paths: int, seed: int = 0) -> dict:
    """The walk's albedo split by order, per column: each a (len(columns),) mean, with the standard error of the total."""
    rng = np.random.default_rng(seed)
    columns = np.asarray(columns)
    column = np.repeat(columns, paths)
    n = column.size
    t = np.radians(theta_deg)
    d = np.broadcast_to(np.array([-np.sin(t), 0.0, -np.cos(t)]), (n, 3)).copy()
    ones = np.ones((n, 1))
    _, _, _, up, alive, _, refl = microsurface.walk(
        d, ones, ones.copy(), alpha, lambda c, rows: _lookup(reflectance, c, column[rows]), rng)
    up, refl = up & alive, refl
    down = ~up & alive

    def mean(mask):
        return mask.reshape(columns.size, paths).mean(axis=1)

    return {"up1": mean(up & (refl == 1)), "up2": mean(up & (refl >= 2)), "down0": mean(down & (refl == 0)),
            "down1": mean(down & (refl >= 1)), "up": mean(up)}


def eq17_albedo(reflectance: np.ndarray, alpha: float, theta_deg: float, columns, side: int = 64) -> np.ndarray:
    """Eq. 17's directional albedo ``E_m[R(theta_d) G1(o)]`` over the normals visible from ``i`` (midpoint quadrature)."""
    u1, u2 = np.meshgrid((np.arange(side) + 0.5) / side, (np.arange(side) + 0.5) / side)
    t = np.radians(max(theta_deg, 1e-3))
    i = np.array([np.sin(t), 0.0, np.cos(t)])
    v = np.broadcast_to(i, (side * side, 3))
    m = microfacet.sample_ggx_visible_normal(v, alpha, u1.ravel(), u2.ravel())
    cos_d = np.clip(np.sum(v * m, axis=-1), 0.0, 1.0)
    o_z = 2.0 * cos_d * m[:, 2] - i[2]
    G1_o = np.where(o_z > 0.0, microfacet.smith_G1(np.clip(o_z, 1e-6, 1.0), alpha), 0.0)
    out = []
    for c in columns:
        out.append(np.mean(_lookup(reflectance, cos_d, np.full(cos_d.size, c))[:, 0] * G1_o))
    return np.array(out)


def model_terms(layer_table, terms, alpha: float, theta_deg: float, columns) -> dict:
    """The model's terms at ``theta`` for the columns: ``E_r``, ``r m``, ``t_b``, ``(1 - r) m`` and Eq. 28's ``(1 - rho) G1``
    (``terms``: the layer's :class:`explorer.physics.multiscatter.LayerTerms`, interpolated between its 2-degree rows)."""
    t = np.radians(theta_deg)
    f_t = _row(layer_table.transmissivity, t)
    at = lambda x: multiscatter.rows_at(np.asarray(x, dtype=np.float64), np.asarray([t]), np.radians(multiscatter.COMPENSATION_STEP_DEG))[0]  # noqa: E731
    E_r, t_b, m, r = at(terms.reflection), at(terms.ballistic), at(terms.missing), at(terms.up)
    cols = np.asarray(columns)
    return {"E_r": E_r[cols], "rm": (r * m)[cols], "t_b": t_b[cols], "down_m": ((1.0 - r) * m)[cols], "eq28": f_t[cols]}


def _row(table: np.ndarray, theta: float) -> np.ndarray:
    x = theta / microfacet.THETA_STEP
    k = min(int(np.floor(x)), table.shape[0] - 2)
    f = x - k
    return table[k].astype(np.float64) * (1.0 - f) + table[k + 1].astype(np.float64) * f


def study(name: str, alpha: float, paths: int) -> list[dict]:
    """The walk's orders, Eq. 17 / Eq. 28 and the model's terms for preset ``name``'s top layer at ``alpha``, per angle of :data:`THETA`."""
    from explorer.materials.brd import load_material
    from explorer.materials.models import model_for
    from explorer.materials.presets import presets_for
    from explorer.materials.models import BraggStackModel
    from explorer.materials.twins import shipped_file

    material = load_material(shipped_file(BraggStackModel))
    values = dict(material.resolve(presets_for(material.path).get(name).values))
    for k in range(1, 4):
        values[f"alpha_{k}"] = float(alpha)
    model = model_for(material, {**values, "multiple_scattering": True})
    table = model.tables[0]
    comp = multiscatter_stack.layer_terms_of(table)
    R = np.ascontiguousarray(table.reflectance, dtype=np.float32)
    rows = []
    for k, theta in enumerate(THETA):
        w = walk_orders(R, alpha, theta, COLUMNS, paths, seed=k)
        mt = model_terms(table, comp, alpha, theta, COLUMNS)
        rows.append({"theta": theta, "walk": w, "model": mt, "eq17": eq17_albedo(R, alpha, theta, COLUMNS)})
    return rows


BEGIN, END = "<!-- multiscatter-orders:begin -->", "<!-- multiscatter-orders:end -->"
STRUCTURE_BEGIN, STRUCTURE_END = "<!-- multiscatter-structure:begin -->", "<!-- multiscatter-structure:end -->"
STRUCTURE_PRESETS = ("figure7_A", "figure1_right_alpha04", "figure1_stacked_pair", "figure7_A_on_base")


def structure_rows(presets, alphas, samples: int = 8192) -> list[dict]:
    """
    The whole structure, luminance of the directional albedo: Eq. 34 (single scattering on the facets, one
    reflection among the layers) against the position-free walk with single scattering on the facets (every
    reflection among the layers, the coating and the base), and the compensated model against the walk with
    the microsurface walk. The first gap is what the layering costs, the second what the facets add to it.
    """
    from explorer.dev.multiscatter_validation import LUMINANCE, THETA as ANGLES
    from explorer.materials.brd import load_material
    from explorer.materials.models import model_for
    from explorer.materials.presets import presets_for
    from explorer.physics.position_free import PositionFree
    from explorer.materials.models import BraggStackModel
    from explorer.materials.twins import shipped_file
    from explorer.views.albedo import albedo_numpy

    material = load_material(shipped_file(BraggStackModel))
    rows = []
    for name in presets:
        for alpha in alphas:
            values = dict(material.resolve(presets_for(material.path).get(name).values))
            for k in range(1, 4):
                values[f"alpha_{k}"] = float(alpha)
            single = model_for(material, {**values, "multiple_scattering": False})
            compensated = model_for(material, {**values, "multiple_scattering": True})
            compensated.full_compensation = True  # the whole lobe at every alpha, as the validation (the fade leaves alpha <= 0.4 out)
            row = {"preset": name, "alpha": alpha, "layers": len(single.stack.layers), "theta": list(ANGLES)}
            for key, model, surface in (("single", single, "single"), ("compensated", compensated, "walk")):
                reference = PositionFree(single.stack, single.tables, surface).albedo(ANGLES, samples, 0).value @ LUMINANCE
                row[f"{key}_gap"] = (albedo_numpy(model, ANGLES) @ LUMINANCE / reference - 1.0).tolist()
            rows.append(row)
    return rows


def structure_table(rows: list[dict]) -> str:
    """The Markdown table of :func:`structure_rows`: the luminance gaps (%) at each angle."""
    angles = " / ".join(f"{t:g}°" for t in rows[0]["theta"])
    lines = [f"| preset | layers | α | Eq. 34 vs walk with single-scattering facets, ΔY at {angles} "
             f"| compensated vs microsurface walk, ΔY at {angles} |", "|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| `{r['preset']}` | {r['layers']} | {r['alpha']:g} | {' / '.join(f'{100 * g:+.1f}' for g in r['single_gap'])} % "
                     f"| {' / '.join(f'{100 * g:+.1f}' for g in r['compensated_gap'])} % |")
    return "\n".join(lines)


def table(rows: list[tuple[str, float, dict]]) -> str:
    """The Markdown table: per preset, alpha and theta, the walk's terms and each model's signed gap (means over the wavelengths)."""
    lines = ["| preset | α | θ | walk: 1st order up | Eq. 17 − walk | model `E_r` − walk | walk: ≥ 2nd order up | model `r m` − walk "
             "| walk: ballistic down | Eq. 28 − walk | model `t_b` − walk | walk: scattered down | model `(1 − r) m` − walk "
             "| walk: up | model up − walk |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for name, alpha, r in rows:
        w, mt = r["walk"], r["model"]

        def gap(a, b):
            return f"{np.mean(a - b):+.3f}"

        lines.append(f"| `{name}` | {alpha:g} | {r['theta']:g}° | {np.mean(w['up1']):.3f} | {gap(r['eq17'], w['up1'])} "
                     f"| {gap(mt['E_r'], w['up1'])} | {np.mean(w['up2']):.3f} | {gap(mt['rm'], w['up2'])} "
                     f"| {np.mean(w['down0']):.3f} | {gap(mt['eq28'], w['down0'])} | {gap(mt['t_b'], w['down0'])} "
                     f"| {np.mean(w['down1']):.3f} | {gap(mt['down_m'], w['down1'])} | {np.mean(w['up']):.3f} "
                     f"| {gap(mt['E_r'] + mt['rm'], w['up'])} |")
    return "\n".join(lines)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python3 -m explorer.dev.multiscatter_orders", description=__doc__.split("\n\n")[0])
    parser.add_argument("--presets", nargs="+", default=list(PRESETS))
    parser.add_argument("--alphas", nargs="+", type=float, default=[0.5, 1.0])
    parser.add_argument("--paths", type=int, default=4000)
    parser.add_argument("--write", action="store_true", help="replace the table of docs/layered_validation.md")
    parser.add_argument("--structure", action="store_true",
                        help="instead: whole structures (Eq. 34 and the compensated model against the position-free walks)")
    args = parser.parse_args(argv)
    if args.structure:
        text = structure_table(structure_rows(STRUCTURE_PRESETS, (0.2, 0.7)))
        print(text)
        if args.write:
            _write(STRUCTURE_BEGIN, STRUCTURE_END, text)
        return 0
    rows = [(name, alpha, r) for name in args.presets for alpha in args.alphas for r in study(name, alpha, args.paths)]
    text = table(rows)
    print(text)
    if args.write:
        _write(BEGIN, END, text)
    return 0


def _write(begin: str, end: str, text: str) -> None:
    """Replace the text between two markers of ``docs/layered_validation.md``."""
    from explorer.dev.multiscatter_validation import PAGE
    from explorer.files import write_text_atomic

    page = PAGE.read_text(encoding="utf-8")
    start, stop = page.index(begin) + len(begin), page.index(end)
    write_text_atomic(PAGE, page[:start] + "\n" + text + "\n" + page[stop:])


if __name__ == "__main__":
    raise SystemExit(main())
