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
from explorer.files import check_output, write_text_atomic
from explorer.physics import dispersion
from explorer.views.spectrum_plot import describe, natural_mirror, spectrum_document, write_plot  # noqa: F401



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
    from explorer.cli.albedo import progress_while

    with progress_while("spectrum"):  # disorder's realisations take seconds
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
