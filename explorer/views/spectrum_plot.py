"""
A natural Bragg mirror's exact spectra as a document and a plot: what ``bragg-explorer spectrum`` prints and
draws (:mod:`explorer.cli.spectrum`) and the specimens' figures (``explorer.dev.specimen_figures``) show.
"""

from __future__ import annotations

import numpy as np

from explorer.errors import LocatedError
from explorer.files import save_figure
from explorer.physics import dispersion
from explorer.physics.natural import NaturalMirror, band_gaps, mirror_spectrum, wavelength_grid


def natural_mirror(values: dict, natural: dict) -> NaturalMirror:
    """The mirror of a material's values (a ``bragg_mirror`` or ``bragg_layer``'s), with the natural ones over them."""
    from explorer.materials.media import index_value
    from explorer.materials.models import host_index

    nh = host_index(natural.get("nh", index_value(values, "nh") if "nh" in values else 0.0))
    try:
        return NaturalMirror(
            n1=natural.get("n1", index_value(values, "n1")), n2=natural.get("n2", index_value(values, "n2")),
            Lambda=float(values["Lambda"]), delta=float(values["delta"]), N=int(round(float(values["N"]))), nh=nh,
            k1=natural.get("k1", float(values.get("k1", 0.0))), k2=natural.get("k2", float(values.get("k2", 0.0))),
            sigma=natural.get("sigma", float(values.get("sigma", 0.0))),
        )
    except ValueError as error:
        raise LocatedError("--set", None, str(error)) from None


def spectrum_document(mirror: NaturalMirror, thetas: list[float], step_nm: float | None = None) -> dict:
    """The ``--json`` document: the grid, the angles and one row per angle of ``R``, ``Rs``, ``Rp``, ``T``, ``A``."""
    wavelengths = wavelength_grid(mirror, step_nm)
    result = mirror_spectrum(mirror, wavelengths, thetas)
    document = {"wavelength_nm": [round(float(w), 6) for w in wavelengths], "theta_deg": [float(t) for t in thetas]}
    for key in ("R", "Rs", "Rp", "T", "A"):
        document[key] = result[key].tolist()
    return document


def write_plot(document: dict, mirror: NaturalMirror, out, title: str) -> None:
    """R, Rs and Rp against wavelength, one panel per angle, the band gaps shaded (as the Spectrum window draws them)."""
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    wavelengths = np.asarray(document["wavelength_nm"])
    thetas = document["theta_deg"]
    figure, axes = plt.subplots(len(thetas), 1, figsize=(7.0, 2.4 * len(thetas) + 0.6), dpi=100, squeeze=False, sharex=True)
    figure.suptitle(title, fontsize=9)
    for row, (theta, ax) in enumerate(zip(thetas, axes[:, 0])):
        gap = band_gaps(mirror, wavelengths, theta)
        ax.fill_between(wavelengths, 0, 1, where=gap, color="0.88", step="mid", label="band gap")
        ax.plot(wavelengths, document["Rs"][row], color="tab:blue", linewidth=0.8, label="R_s")
        ax.plot(wavelengths, document["Rp"][row], color="tab:red", linewidth=0.8, label="R_p")
        ax.plot(wavelengths, document["R"][row], color="black", linewidth=1.2, label="R")
        ax.plot(wavelengths, document["A"][row], color="tab:brown", linewidth=0.8, linestyle="--", label="A")
        ax.set_ylim(0, 1.02)
        ax.set_xlim(wavelengths[0], wavelengths[-1])
        ax.set_ylabel(f"θ = {theta:g}°")
        if row == 0:
            ax.legend(loc="upper right", fontsize=7, ncols=5)
    axes[-1, 0].set_xlabel("wavelength (nm)")
    figure.tight_layout()
    save_figure(figure, out)


def describe(mirror: NaturalMirror) -> str:
    show = dispersion.describe
    parts = [f"n1={show(mirror.n1)}", f"n2={show(mirror.n2)}", f"Lambda={mirror.Lambda:g}", f"delta={mirror.delta:g}",
             f"N={mirror.N}", f"nh={'n1' if mirror.nh is None else show(mirror.nh)}"]
    parts += [f"{name}={getattr(mirror, name):g}" for name in ("k1", "k2", "sigma") if getattr(mirror, name)]
    return " ".join(parts)
