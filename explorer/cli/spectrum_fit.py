"""
``design MATERIAL --target-spectrum FILE.csv``: the natural Bragg mirror whose reflectance best matches a
measured spectrum (:mod:`explorer.physics.spectral_fit`), its residual, and a plot of measured against fitted.

The file holds ``wavelength_nm,R`` rows inside 360-830 nm, an optional header; R is a fraction, or in
percent when the header says so (``R_percent``, ``R (%)``) or when a value exceeds 1.5 (detected and said).
"""

from __future__ import annotations

import csv
import json
import math

import click
import numpy as np

from explorer.cli.materials import load_mirror, warn
from explorer.cli.spectrum import INDEX_PARAMETERS, NATURAL_PARAMETERS, describe
from explorer.errors import LocatedError
from explorer.files import check_output, save_figure
from explorer.physics import dispersion
from explorer.physics.spectral_fit import RANGES, fit_spectrum

#: The fewest measured wavelengths a fit takes.
MIN_POINTS = 8


def read_measured(path: str) -> tuple[np.ndarray, np.ndarray, str]:
    """``(wavelengths, R as a fraction, note)`` from a ``wavelength_nm,R`` CSV; a one-line error at a bad line."""
    try:
        text = open(path, encoding="utf-8").read()
    except FileNotFoundError:
        raise LocatedError(path, None, "no such file") from None
    except (OSError, UnicodeDecodeError) as error:
        raise LocatedError(path, None, f"cannot be read ({type(error).__name__})") from None
    rows, percent_header = [], False
    for number, row in enumerate(csv.reader(text.splitlines()), start=1):
        cells = [c.strip() for c in row]
        if not any(cells) or cells[0].startswith("#"):
            continue
        if not rows and not dispersion._numeric(cells[0]):
            header = ",".join(cells).lower()
            if not header.startswith("wavelength"):
                raise LocatedError(path, number, f"the header must be wavelength_nm,R (got {header[:60]!r})")
            percent_header = "%" in header or "percent" in header
            continue
        if len(cells) != 2 or not all(dispersion._numeric(c) for c in cells):
            raise LocatedError(path, number, f"expected two numbers wavelength_nm,R (got {','.join(cells)[:60]!r})")
        wavelength, R = float(cells[0]), float(cells[1])
        if not (math.isfinite(wavelength) and math.isfinite(R)) or R < 0.0:
            raise LocatedError(path, number, "needs a finite wavelength and R >= 0")
        if not dispersion.RANGE_NM[0] <= wavelength <= dispersion.RANGE_NM[1]:
            raise LocatedError(path, number, f"{wavelength:g} nm is outside {dispersion.RANGE_NM[0]:g}-{dispersion.RANGE_NM[1]:g} nm")
        if rows and wavelength <= rows[-1][0]:
            raise LocatedError(path, number, f"wavelengths must increase ({wavelength:g} after {rows[-1][0]:g})")
        rows.append((wavelength, R))
    if len(rows) < MIN_POINTS:
        raise LocatedError(path, None, f"needs at least {MIN_POINTS} rows wavelength_nm,R")
    table = np.array(rows)
    if percent_header:
        note = "R in percent (header)"
    elif table[:, 1].max() > 1.5:
        note = "R in percent (detected: values above 1.5)"
    else:
        note = "R as a fraction"
    R = table[:, 1] / (100.0 if note.startswith("R in percent") else 1.0)
    if R.max() > 1.0 + 1e-9:
        raise LocatedError(path, None, f"a reflectance above 1 ({R.max():.3g}) after reading it as {note}")
    return table[:, 0], R, note


def parse_fixed(fixes) -> dict:
    """``--fix NAME=VALUE``: an index as a number or a medium, ``N`` an integer, the others numbers."""
    from explorer.materials.brd import parse_assignment

    known = set(RANGES) | {"N", "nh", "sigma"}
    fixed: dict = {}
    for text in fixes:
        name, value = parse_assignment(text)
        if name not in known:
            raise LocatedError("--fix", None, f"{name!r} is not fitted (one of {', '.join(sorted(known))})")
        if name in INDEX_PARAMETERS and dispersion.is_dispersion_text(value):
            fixed[name] = dispersion.dispersion_named(value, origin=f"--fix {name}")
            continue
        try:
            number = float(value)
        except ValueError:
            raise LocatedError("--fix", None, f"{name}={value!r}: a number") from None
        if name == "N":
            if number != round(number) or not 1 <= number <= 1000:
                raise LocatedError("--fix", None, f"N={value!r}: an integer in [1, 1000]")
            fixed[name] = int(number)
        elif name in NATURAL_PARAMETERS:
            low, high = NATURAL_PARAMETERS[name]
            if not low <= number <= high:
                raise LocatedError("--fix", None, f"{name}={value!r}: a number in [{low:g}, {high:g}]")
            fixed[name] = number
        else:
            low, high = RANGES.get(name, (1.0, 3.0))
            if not (math.isfinite(number) and (name != "nh" or number >= 1.0) and number >= 0.0):
                raise LocatedError("--fix", None, f"{name}={value!r}: out of range")
            fixed[name] = number
    return fixed


def write_fit_plot(fit, out: str, title: str) -> None:
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    figure, ax = plt.subplots(figsize=(7.0, 3.2), dpi=100)
    ax.plot(fit.wavelength_nm, fit.measured, "o", markersize=2.5, color="0.4", label="measured")
    ax.plot(fit.wavelength_nm, fit.fitted, color="black", linewidth=1.2, label=f"fitted (RMS {fit.rms:.4f})")
    ax.set_xlabel("wavelength (nm)")
    ax.set_ylabel("R")
    ax.set_title(title, fontsize=8)
    ax.legend(fontsize=8)
    figure.tight_layout()
    save_figure(figure, out)


def parse_free(text: str | None, fixed: dict, loaded) -> bool:
    """
    ``--free NAME,...``: only these are fitted, the others held at the material's values (added to ``fixed``;
    a host below 1 stays "the host is n1"). Returns whether ``sigma`` is free (else 0 unless fixed).
    """
    if text is None:
        return False
    known = set(RANGES) | {"N", "nh", "sigma"}
    names = [n.strip() for n in text.split(",") if n.strip()]
    if not names:
        raise LocatedError("--free", None, f"{text!r}: name at least one of {', '.join(sorted(known))}")
    for name in names:
        if name not in known:
            raise LocatedError("--free", None, f"{name!r} is not fitted (one of {', '.join(sorted(known))})")
        if name in fixed:
            raise LocatedError("--free", None, f"{name} is also fixed by --fix")
    values = loaded.resolve({})
    for name in sorted(known - set(names) - set(fixed)):
        if name == "nh" and float(values["nh"]) < 1.0:
            continue
        fixed[name] = int(round(float(values[name]))) if name == "N" else float(values[name])
    return "sigma" in names


def fit_command(material: str, path: str, theta: float, fixes, as_json: bool, plot_out: str | None, seed: int,
                free: str | None = None) -> None:
    """What ``design --target-spectrum`` prints: the structure as ``--set`` values, the RMS residual; ``--plot``."""
    if plot_out is not None:
        check_output(plot_out, (".png",))
    loaded = load_mirror(material, "--target-spectrum fits")
    wavelengths, measured, note = read_measured(path)
    fixed = parse_fixed(fixes)
    free_sigma = parse_free(free, fixed, loaded)
    from explorer.cli.albedo import progress_while

    with progress_while("design --target-spectrum"):
        fit = fit_spectrum(wavelengths, measured, theta, fixed, seed=seed, free_sigma=free_sigma)
    sets = " ".join(f"--set {k}={dispersion.describe(v) if isinstance(v, dispersion.Dispersion) else f'{v:.6g}'}"
                    for k, v in {**fixed, **fit.values}.items())
    if plot_out is not None:
        write_fit_plot(fit, plot_out, f"{describe(fit.mirror)} at {theta:g}°")
    if as_json:
        click.echo(json.dumps({"values": {k: (v.name if isinstance(v, dispersion.Dispersion) else v) for k, v in {**fixed, **fit.values}.items()},
                               "rms": fit.rms, "theta_deg": theta, "reading": note, "seconds": round(fit.seconds, 2),
                               "wavelength_nm": fit.wavelength_nm.tolist(), "measured": fit.measured.tolist(),
                               "fitted": fit.fitted.tolist()}))
        return
    warn(f"{path}: {note}") if note.endswith("1.5)") else None
    click.echo(f"{material}: {sets}")
    click.echo(f"RMS of R (fitted - measured) over {fit.wavelength_nm.size} wavelengths: {fit.rms:.4f} ({fit.seconds:.1f} s)")
    click.echo(f"spectrum: bragg-explorer spectrum {material} {sets} --theta {theta:g} --plot fit.png")
