"""
``bragg-explorer spectrum``: a Bragg mirror's exact spectral reflectance R(lambda) (s, p and their mean),
transmittance and absorptance at a few incidence angles, as JSON, CSV or a plot; registered by
:mod:`explorer.cli.commands`.

Its values are the material's (``--preset``, ``--params``, ``--set``), and what natural structures add
(:mod:`explorer.physics.natural`): an index may name a medium (``--set n2=chitin``, or a ``.csv``/``.toml``
file, :mod:`explorer.physics.dispersion`), ``k1``, ``k2`` (extinction) and ``sigma`` (thickness disorder).
"""

from __future__ import annotations

import csv
import io
import json

import click
import numpy as np

from explorer.cli.materials import load_mirror, resolve_values
from explorer.errors import LocatedError
from explorer.files import atomic_output, check_output, write_text_atomic
from explorer.physics import dispersion
from explorer.physics.natural import NaturalMirror, band_gaps, mirror_spectrum, wavelength_grid



#: Index parameters that may name a medium.
INDEX_PARAMETERS = ("n1", "n2", "nh")
#: What natural structures add to a mirror, with their ranges (taken here where the material does not declare them).
NATURAL_PARAMETERS = {"k1": (0.0, 10.0), "k2": (0.0, 10.0), "sigma": (0.0, 0.3)}
#: The most angles one command computes.
MAX_ANGLES = 32


def parse_thetas(text: str) -> list[float]:
    """``--theta 0,30,60``: degrees in [0, 90] in the outer medium."""
    try:
        thetas = [float(part) for part in text.split(",")]
    except ValueError:
        thetas = []
    if not thetas or len(thetas) > MAX_ANGLES or not all(np.isfinite(t) and 0.0 <= t <= 90.0 for t in thetas):
        raise click.BadParameter(f"{text[:60]!r} is not a list of 1 to {MAX_ANGLES} angles in [0, 90] degrees (e.g. 0,30,60)",
                                 param_hint="--theta")
    return thetas


def split_natural(loaded, assignments, preset_values: dict | None = None) -> tuple[list[str], dict]:
    """
    ``--set`` assignments the material takes as they are, and the natural ones: an index naming a medium,
    and ``k1``, ``k2``, ``sigma`` where the material does not declare them (checked against their ranges).
    """
    from explorer.materials.brd import parse_assignment

    declared = {p.name for p in loaded.parameters}
    passed, natural = [], {}
    for text in assignments:
        name, value = parse_assignment(text)
        if name in INDEX_PARAMETERS and dispersion.is_dispersion_text(value):
            medium = dispersion.dispersion_named(value, origin=f"--set {name}")
            if f"medium_{name}" in declared and medium.name in dispersion.LIBRARY:
                passed.append(text)  # the material selects it (medium_NAME)
            else:
                natural[name] = medium
        elif name in NATURAL_PARAMETERS and name not in declared:
            low, high = NATURAL_PARAMETERS[name]
            try:
                number = float(value)
            except ValueError:
                number = float("nan")
            if not (np.isfinite(number) and low <= number <= high):
                raise LocatedError("--set", None, f"{name}={value!r}: a number in [{low:g}, {high:g}]")
            natural[name] = number
        else:
            passed.append(text)
    return passed, natural


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


def csv_text(document: dict) -> str:
    """One row per wavelength: ``wavelength_nm``, then ``R``, ``Rs``, ``Rp``, ``T``, ``A`` at each angle (``R@30`` ...)."""
    stream = io.StringIO()
    writer = csv.writer(stream, lineterminator="\n")
    keys = ("R", "Rs", "Rp", "T", "A")
    writer.writerow(["wavelength_nm"] + [f"{key}@{theta:g}" for theta in document["theta_deg"] for key in keys])
    for i, wavelength in enumerate(document["wavelength_nm"]):
        writer.writerow([f"{wavelength:g}"] + [f"{document[key][row][i]:.9g}"
                                                for row in range(len(document["theta_deg"])) for key in keys])
    return stream.getvalue()


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
    with atomic_output(out, (".png",)) as temporary:
        try:
            with open(temporary, "wb") as stream:
                figure.savefig(stream, format="png")
        finally:
            plt.close(figure)


def describe(mirror: NaturalMirror) -> str:
    show = dispersion.describe
    parts = [f"n1={show(mirror.n1)}", f"n2={show(mirror.n2)}", f"Lambda={mirror.Lambda:g}", f"delta={mirror.delta:g}",
             f"N={mirror.N}", f"nh={'n1' if mirror.nh is None else show(mirror.nh)}"]
    parts += [f"{name}={getattr(mirror, name):g}" for name in ("k1", "k2", "sigma") if getattr(mirror, name)]
    return " ".join(parts)


@click.command("spectrum")
@click.argument("material", type=click.Path(dir_okay=False))
@click.option("--preset", metavar="NAME", help="Start from a preset of the material (bragg-explorer presets); --set overrides it.")
@click.option("--params", "params_file", metavar="FILE", help="A parameter set (JSON or .bparam); over --preset, under --set.")
@click.option("--set", "assignments", multiple=True, metavar="NAME=VALUE",
              help="A parameter (repeatable); n1, n2, nh may name a medium (info --dispersions) or a .csv/.toml file; "
                   "also k1, k2 (extinction, >= 0) and sigma (thickness disorder, 0-0.3).")
@click.option("--theta", "theta_text", default="0", show_default=True, metavar="A,B,...",
              help="Incidence angles in degrees in the outer medium (the host).")
@click.option("--json", "as_json", is_flag=True, help="Print the spectra as JSON.")
@click.option("--csv", "csv_out", type=click.Path(dir_okay=False), metavar="FILE", help="Write the spectra as CSV.")
@click.option("--plot", "plot_out", type=click.Path(dir_okay=False), metavar="FILE.png", help="Plot the spectra with the band gaps.")
def spectrum_command(material, preset, params_file, assignments, theta_text, as_json, csv_out, plot_out):
    """The exact spectral reflectance R(lambda) of a Bragg mirror (s, p, their mean; T and A) from 360 to 830 nm,
    with absorbing, dispersive layers and thickness disorder."""
    thetas = parse_thetas(theta_text)
    for out, suffixes in ((csv_out, (".csv",)), (plot_out, (".png",))):
        if out is not None:
            check_output(out, suffixes)
    loaded = load_mirror(material, "spectrum takes")
    passed, natural = split_natural(loaded, assignments)
    values = resolve_values(loaded, preset, params_file, passed)
    mirror = natural_mirror(values, natural)
    document = spectrum_document(mirror, thetas, float(values.get("wavelength_step", 1.0)))
    if csv_out is not None:
        write_text_atomic(csv_out, csv_text(document), (".csv",))
    if plot_out is not None:
        write_plot(document, mirror, plot_out, describe(mirror))
    if as_json:
        click.echo(json.dumps(document))
    elif csv_out is None and plot_out is None:
        click.echo(f"{describe(mirror)}")
        for row, theta in enumerate(thetas):
            R = np.asarray(document["R"][row])
            peak = int(np.argmax(R))
            click.echo(f"  theta {theta:g}: R peaks at {document['wavelength_nm'][peak]:g} nm ({R[peak]:.4f}); "
                       f"mean R {R.mean():.4f}, mean A {np.mean(document['A'][row]):.4f} (--json, --csv or --plot for the spectra)")


def dispersions_listing(as_json: bool) -> str:
    """``info --dispersions``: each shipped medium with its formula, citation and n + ik at 400, 550, 700 nm."""
    rows = []
    for entry in dispersion.LIBRARY.values():
        at = {f"{w:g}": [round(float(v.real), 4), round(float(v.imag), 4)] for w, v in zip((400, 550, 700), entry.index([400.0, 550.0, 700.0]))}
        rows.append({"name": entry.name, "formula": entry.formula, "citation": entry.citation, "n_k_at_nm": at})
    if as_json:
        return json.dumps(rows, indent=2)
    lines = [f"media an index may name (n2=NAME), {dispersion.RANGE_NM[0]:g}-{dispersion.RANGE_NM[1]:g} nm; "
             "or a file: NAME.csv (wavelength_nm,n,k) or NAME.toml (Cauchy or Sellmeier coefficients)"]
    for row in rows:
        sample = ", ".join(f"{n:.3f}+{k:.3f}i @ {w} nm" for w, (n, k) in row["n_k_at_nm"].items())
        lines += [f"{row['name']}: {row['formula']}", f"    {row['citation']}", f"    {sample}"]
    return "\n".join(lines)
