"""
``bragg-explorer design``: the structure of a Bragg mirror, rough Bragg layer or thin film from the colours
wanted at a few angles (:mod:`explorer.design`), registered by :mod:`explorer.cli.commands`.

A target is ``--target THETA:COLOUR``: THETA in degrees in the outer medium, COLOUR ``#RRGGBB`` (sRGB) or
``r,g,b`` (linear RGB, the convention of ``render``'s ``.npy``, kept as it is even outside [0, 1]). A strip
(``--target-strip IMAGE --theta-range A,B``: a ``.png`` in sRGB or a ``.npy``/``.exr`` of linear RGB,
column ``i`` of ``W`` at ``A + (B - A)(i + 0.5) / W`` degrees, as the gradient view draws it) gives
:data:`STRIP_TARGETS` targets, each the mean of its column's rows.
"""

from __future__ import annotations

import json
import os
import sys

from dataclasses import replace

import click
import numpy as np

PROG = "bragg-explorer"
#: Targets taken from a strip, at evenly spaced columns.
STRIP_TARGETS = 5
#: Said under targets left above the reachable threshold: the search is not exhaustive, so "not reachable"
#: means none closer was found (the round trip, docs/design.md: in one search 13 of 50 random mirrors end above 2, most
#: high-order; with --tries 8, 4).
SEARCH_CAVEAT = ("the search is not exhaustive (it misses some thick, high-order stacks): more --tries search on "
                 "from fresh samples and the best so far, --guess NAME=VALUE,... adds a structure you expect")
#: Searches per design by default: the round trip reaches 92 % of random mirrors within ΔE2000 1 in at
#: most 8, 64 % in one (docs/design.md); a design its first search reaches stops there (~4 s).
DEFAULT_TRIES = 8
#: The most searches ``--tries`` asks for (each ~4 s).
MAX_TRIES = 50


def _progress_line(tries: int):
    """With more than one try, a ``progress(fraction, stage)`` that says on stderr when each try starts."""
    if tries == 1:
        return None
    said = set()

    def progress(fraction: float, stage: str) -> None:
        head = stage.partition(":")[0]
        if head.startswith("try ") and head not in said:
            said.add(head)
            click.echo(f"{PROG} design: {head}", err=True)

    return progress


def _fail(message: str) -> None:
    click.echo(f"{PROG}: error: {message}", err=True)
    sys.exit(1)


def load(path):
    """A material file or a built-in's name (as ``render`` takes it), its warnings on stderr."""
    from explorer.materials.brd import load_material
    from explorer.resources import material_path

    material = load_material(material_path(path))
    for warning in material.warnings:
        click.echo(f"{PROG}: warning: {warning}", err=True)
    return material


def srgb_to_linear(encoded) -> np.ndarray:
    """sRGB-encoded values in [0, 1] to linear RGB (the inverse of the PNGs' encode)."""
    import colour

    return np.asarray(colour.cctf_decoding(np.asarray(encoded, dtype=np.float64), function="sRGB"))


def parse_colour(text: str, where: str = "--target") -> np.ndarray:
    """``#RRGGBB`` (sRGB) or ``r,g,b`` (linear) as linear RGB; a :class:`click.UsageError` otherwise."""
    from explorer.design import DesignError, check_target_rgb

    text = text.strip()
    if text.startswith("#"):
        digits = text[1:]
        if len(digits) != 6 or any(c not in "0123456789abcdefABCDEF" for c in digits):
            raise click.UsageError(f"{where}: {text!r} is not #RRGGBB")
        rgb = srgb_to_linear([int(digits[k : k + 2], 16) / 255.0 for k in (0, 2, 4)])
    else:
        try:
            rgb = np.array([float(v) for v in text.split(",")])
        except ValueError:
            raise click.UsageError(f"{where}: {text!r} is not #RRGGBB or r,g,b") from None
        if rgb.size != 3:
            raise click.UsageError(f"{where}: {text!r} is not #RRGGBB or r,g,b (three numbers)")
    try:
        return check_target_rgb(rgb, f"{where} {text}")
    except DesignError as error:
        raise click.UsageError(str(error)) from None


def parse_target(text: str):
    """``THETA:COLOUR`` as a :class:`explorer.design.Target`."""
    from explorer.design import Target

    theta_text, sep, colour_text = text.partition(":")
    if not sep:
        raise click.UsageError(f"--target {text!r}: expected THETA:COLOUR (e.g. 30:#3f9f4f or 30:0.1,0.4,0.1)")
    try:
        theta = float(theta_text)
    except ValueError:
        theta = float("nan")
    if not (np.isfinite(theta) and 0.0 <= theta < 90.0):
        raise click.UsageError(f"--target {text!r}: THETA must be a number of degrees in [0, 90)")
    return Target(theta, tuple(float(c) for c in parse_colour(colour_text, f"--target {theta_text}")))


def strip_targets(path: str, theta_range: str | None, count: int = STRIP_TARGETS):
    """Targets read from a strip image over ``theta_range`` (``A,B`` degrees)."""
    from explorer.design import DesignError, targets_from_strip
    from explorer.views.images import clipped_codes, read_linear_image

    if theta_range is None:
        raise click.UsageError("--target-strip needs --theta-range A,B (degrees at its left and right edges)")
    try:
        a, b = (float(v) for v in theta_range.split(","))
    except ValueError:
        raise click.UsageError(f"--theta-range {theta_range!r}: expected A,B in degrees") from None
    try:
        image = read_linear_image(path)
        targets = targets_from_strip(image, a, b, count, clipped_codes(path))
    except (ValueError, DesignError) as error:
        raise click.UsageError(f"--target-strip {error}") from None
    bounded = [t for t in targets if t.bounded]
    if bounded:
        words = {-1: "at most", 1: "at least"}
        described = "; ".join(f"{t.theta_deg:.3g} deg " + ", ".join(f"{'rgb'[c]} {words[b]} {t.rgb[c]:.3g}"
                                                                    for c, b in enumerate(t.bounds) if b)
                              for t in bounded)
        click.echo(f"{PROG}: note: {path}: channels at the image's limit (0 or 255) are clipped colours, taken as "
                   f"bounds, not values: {described}. For exact targets, render the strip to .npy or .exr "
                   "(linear, unclipped).", err=True)
    return targets


def _named_values(option: str, items, model, material_model: str, expected: str = "NAME=VALUE",
                  media: dict | None = None) -> dict[str, float]:
    """
    ``NAME=VALUE`` items of ``option`` as design values: known names, finite values, each name once; with
    ``media`` (a dict it fills), an index may name a medium (``n2=chitin``, a file) instead.
    """
    from explorer.design.media import MEDIUM_PARAMETERS
    from explorer.errors import LocatedError
    from explorer.physics.dispersion import dispersion_named

    values: dict[str, float] = {}
    for item in items:
        name, sep, value_text = item.partition("=")
        name = name.strip()
        if not sep:
            raise click.UsageError(f"{option} {item!r}: expected {expected}")
        if name not in model.parameters:
            raise click.UsageError(f"{option} {name}: not a design parameter of {material_model} ({', '.join(model.parameters)})")
        try:
            value = float(value_text)
        except ValueError:
            value = float("nan")
        if not np.isfinite(value) and option == "--fix" and name in MEDIUM_PARAMETERS and value_text.strip() \
                and not value_text.strip().lower().startswith(("nan", "inf", "-inf", "+inf")):
            if media is None:
                raise click.UsageError(f"{option} {item!r}: painting takes an index as a number (the colour design "
                                       f"and --target-spectrum take media)")
            if not model.optical:
                raise click.UsageError(f"{option} {item!r}: the colour design takes media for a Bragg mirror's indices only")
            if name in values or name in media:
                raise click.UsageError(f"{option} {name}: given twice")
            try:
                media[name] = dispersion_named(value_text.strip(), origin=f"{option} {name}")
            except LocatedError as error:
                raise click.UsageError(str(error)) from None
            continue
        if not np.isfinite(value):
            raise click.UsageError(f"{option} {item!r}: the value must be a finite number")
        if name in values or (media is not None and name in media):
            raise click.UsageError(f"{option} {name}: given twice")
        values[name] = value
    return values


def parse_fixes(fixes, free, material, media: dict | None = None):
    """
    ``--fix NAME=VALUE`` and ``--free NAME,...`` as the fixed values (every design parameter not free); the
    indices ``--fix`` holds at media go into ``media`` (a dict it fills) instead.
    """
    from explorer.design import design_model

    model = design_model(material.model)
    values = material.resolve({})
    fixed = _named_values("--fix", fixes, model, material.model, media=media)
    media = {} if media is None else media
    if free is not None:
        names = [n.strip() for n in free.split(",") if n.strip()]
        if not names:
            raise click.UsageError(f"--free {free!r}: name at least one parameter ({', '.join(model.parameters)})")
        for name in names:
            if name not in model.parameters:
                raise click.UsageError(f"--free {name}: not a design parameter of {material.model} ({', '.join(model.parameters)})")
            if name in fixed or name in media:
                raise click.UsageError(f"--free {name}: also fixed by --fix")
        for name in model.parameters:
            if name not in names and name not in fixed and name not in media:
                if name in model.held and float(values[name]) == 0.0:
                    continue  # held at 0 by the search (absorption, disorder off): not reported
                fixed[name] = float(values[name])  # not free: the material's default
    return fixed


def parse_guess(text: str, material) -> dict[str, float]:
    """``--guess NAME=VALUE,...``: a structure to start from, the parameters it omits at the material's defaults."""
    from explorer.design import design_model

    model = design_model(material.model)
    defaults = material.resolve({})
    guess = _named_values("--guess", [part.strip() for part in text.split(",")], model, material.model, "NAME=VALUE,...")
    return {name: guess.get(name, float(defaults[name])) for name in model.parameters}


def render_command(material_name: str, values: dict, material=None) -> str:
    """The ``render`` command line that shows the designed structure's θ strip (the material's preferred method:
    Bragg's converged table, the film's Fourier m = 3, within ~0.002 of the reference)."""
    from explorer.materials.twins import capabilities_of

    sets = " ".join(f"--set {k}={v:.6g}" if isinstance(v, float) else f"--set {k}={v}" for k, v in values.items())
    methods = capabilities_of(material).methods if material is not None else None
    best = methods.preferred_member() if methods is not None else None
    method = f" --set method={int(best)}" if best is not None else ""
    from explorer.cli.materials import command_prefix

    return f"{command_prefix()} render {material_name} --view gradient {sets}{method} --out design.png"


@click.command("design")
@click.argument("material", type=click.Path(dir_okay=False))
@click.option("--target", "target_texts", multiple=True, metavar="THETA:COLOUR",
              help="A colour wanted at THETA degrees: #RRGGBB (sRGB) or r,g,b (linear, as render's .npy). Repeatable.")
@click.option("--target-strip", metavar="IMAGE", help="Targets from a strip (.png, 8 or 16 bits, sRGB; .npy or .exr linear), theta across.")
@click.option("--theta-range", metavar="A,B", help="--target-strip: theta (degrees) at its left and right edges.")
@click.option("--fix", "fixes", multiple=True, metavar="NAME=VALUE", help="Hold a design parameter (repeatable); n1, n2 and nh of a mirror may name a medium "
              "(n2=chitin, melanin, a .csv or .toml file): its dispersion and absorption.")
@click.option("--free", metavar="NAME,...", help="Search only these parameters; the others keep the material's defaults.")
@click.option("--guess", "guess_texts", multiple=True, metavar="NAME=VALUE,...",
              help="A structure to start from (omitted parameters: the material's defaults); it joins the first pass. Repeatable.")
@click.option("--json", "as_json", is_flag=True, help="Print the result as JSON (colours linear RGB).")
@click.option("--target-spectrum", metavar="FILE.csv",
              help="Fit a measured reflectance instead (wavelength_nm,R as a fraction or in %): least squares in R(lambda); "
                   "--fix may name media (n2=chitin).")
@click.option("--theta", "spectrum_theta", type=click.FloatRange(0.0, 89.9), default=0.0, show_default=True,
              help="--target-spectrum: the measurement's incidence angle in degrees.")
@click.option("--plot", "spectrum_plot", type=click.Path(dir_okay=False), metavar="FILE.png",
              help="--target-spectrum: plot the measured against the fitted spectrum.")
@click.option("--seed", type=click.IntRange(min=0), default=0, show_default=True, help="The first pass's Sobol scrambling (>= 0).")
@click.option("--tries", type=click.IntRange(min=1, max=MAX_TRIES), default=DEFAULT_TRIES, show_default=True, metavar="K",
              help="Search up to K times until every target is within ΔE2000 1, each from fresh samples and the best "
                   "structure so far (~4 s each; 1: one search).")
@click.option("--target-image", metavar="IMAGE", help="Paint: the colours wanted per pixel at the first angle (.png 8/16 bits sRGB, "
              ".exr/.npy linear; alpha masks pixels out); writes structure maps to --out-maps.")
@click.option("--target-image-2", metavar="IMAGE", help="Paint: the colours at the second angle (the same size).")
@click.option("--angles", "angles_text", metavar="A[,B]", help="Paint: the images' angles in degrees (default 0, or 0,45 with two images).")
@click.option("--out-maps", metavar="DIR", help="Paint: the folder of the maps (one EXR per free parameter), params.json, ΔE2000 maps, report.")
@click.option("--workers", type=click.IntRange(min=1), help="Paint: a local Dask cluster of this many workers (default one per core).")
@click.option("--scheduler", metavar="ADDRESS", help="Paint: an existing Dask cluster's scheduler (tcp://host:8786) instead.")
@click.option("--save", metavar="FILE", help="Also write the structure as a parameter set (FILE.json, or BRDF Explorer's .bparam) "
              "that render, export and open take with --params.")
def design_command(material, target_texts, target_strip, theta_range, fixes, free, guess_texts, as_json, target_spectrum,
                   spectrum_theta, spectrum_plot, seed, tries, target_image, target_image_2, angles_text, out_maps, workers,
                   scheduler, save):
    """Design the structure of MATERIAL (one whose twin declares a design model: bragg_mirror, bragg_layer: its
    specular colour, thin_film, or a plugin's) whose colours at the target angles come closest to the targets (CIEDE2000).

    Prints the structure as --set values, a render command line, and per target the achieved colour
    (converged spectral) and its ΔE2000; a target no structure in the declared ranges reaches is reported
    as not reachable, with the closest structure found.
    """
    from explorer.errors import LocatedError
    from explorer.design import REACHABLE_DELTA_E, DesignError, design, design_model, ranges_of
    from explorer.resources import display_path

    paint_options = (target_image_2, angles_text, out_maps, workers, scheduler)
    if target_image is not None:
        from explorer.cli.paint import paint_command

        if target_texts or target_strip or target_spectrum or guess_texts or save:
            raise click.UsageError("--target-image paints alone: no --target, --target-strip, --target-spectrum, --guess or --save")
        if out_maps is None:
            raise click.UsageError("--target-image needs --out-maps DIR (where the maps go)")
        from explorer.errors import LocatedError
        from explorer.design import DesignError, design_model

        given = click.get_current_context().get_parameter_source("tries") == click.core.ParameterSource.COMMANDLINE
        try:
            loaded = load(material)
            fixed = parse_fixes(fixes, free or ",".join(design_model(loaded.model).paint_free) or None, loaded)
        except (LocatedError, DesignError) as error:
            _fail(str(error))
        paint_command(loaded, fixed, target_image, target_image_2, angles_text, out_maps, workers, scheduler, seed, as_json,
                      tries if given else None)
        return
    if any(option is not None for option in paint_options):
        raise click.UsageError("--target-image-2, --angles, --out-maps, --workers and --scheduler go with --target-image")
    if target_spectrum is not None:
        from explorer.cli.spectrum_fit import fit_command

        if target_texts or target_strip or guess_texts:
            raise click.UsageError("--target-spectrum fits alone: no --target, --target-strip or --guess")
        fit_command(material, target_spectrum, spectrum_theta, fixes, as_json, spectrum_plot, seed, free)
        return
    try:
        loaded = load(material)
        design_model(loaded.model)
        targets = [parse_target(t) for t in target_texts]
        if target_strip is not None:
            targets += strip_targets(target_strip, theta_range)
        elif theta_range is not None:
            raise click.UsageError("--theta-range goes with --target-strip")
        if not targets:
            raise click.UsageError("give at least one --target THETA:COLOUR or --target-strip IMAGE")
        media: dict = {}
        fixed = parse_fixes(fixes, free, loaded, media)
        guesses = [parse_guess(text, loaded) for text in guess_texts]
        # The held parameters (k1, k2, sigma: 0 unless fixed) --free names are searched too.
        released = [name for name in (free or "").split(",") if name.strip() in design_model(loaded.model).held]
        result = design(loaded.model, targets, ranges_of(loaded), fixed, seed=seed, guesses=guesses, tries=tries,
                        progress=_progress_line(tries), media=media, free=[name.strip() for name in released])
        # A medium is reported by its name (render and --save take it so), not the number that stood for it.
        result = replace(result, values={**result.values, **{k: v.name for k, v in media.items()}})
    except (LocatedError, DesignError) as error:
        _fail(str(error))
    name = display_path(loaded.path)
    unreachable = [t for t, ok in zip(result.targets, result.reachable) if not ok]
    if save is not None:
        _save_structure(loaded, result.values, save)
    if as_json:
        click.echo(json.dumps(result.as_json(name), indent=2))
        for t, d in zip(result.targets, result.delta_e2000):
            if d > REACHABLE_DELTA_E:
                click.echo(f"{PROG}: target at {t.theta_deg:g} degrees not reachable (closest: ΔE2000 {d:.2f})", err=True)
        if unreachable:
            click.echo(f"{PROG}: {SEARCH_CAVEAT}", err=True)
        return
    sets = " ".join(f"--set {k}={v:.6g}" if isinstance(v, float) else f"--set {k}={v}" for k, v in result.values.items())
    click.echo(f"{name}: {sets}")
    for t, a, d, ok in zip(result.targets, result.achieved_rgb, result.delta_e2000, result.reachable):
        note = "" if ok else "  not reachable"
        click.echo(f"  theta {t.theta_deg:5.1f}: target {np.round(t.rgb, 4).tolist()} achieved {np.round(a, 4).tolist()} "
                   f"ΔE2000 {d:.2f}{note}")
    tried = f" ({result.tries} searches)" if result.tries > 1 else ""
    click.echo(f"median ΔE2000 {result.median_delta_e2000:.2f}, {result.seconds:.1f} s{tried}")
    if unreachable:
        click.echo(f"not reachable: {len(unreachable)} of {len(result.targets)} targets (ΔE2000 > {REACHABLE_DELTA_E:g}); "
                   "the structure above is the closest found")
        click.echo(SEARCH_CAVEAT)
    click.echo(f"render: {render_command(name, result.values, loaded)}")


def _save_structure(material, values: dict, path: str) -> None:
    """The designed structure as a parameter set at ``path`` (the file's other values at its opening ones: the tabulated method)."""
    from explorer.app.parameter_files import ParameterFileError, save_values
    from explorer.materials.methods import opening_values

    try:
        save_values(path, material, material.resolve({**opening_values(material), **values}))
    except (OSError, ParameterFileError) as error:
        _fail(f"{path}: cannot write the parameter set ({' '.join(str(error).split())[:160]})")
    click.echo(f"{PROG}: wrote {path} (render, export and open take it with --params {path})", err=True)


def run_design_bench(count: int = 50, seed: int = 0, as_json: bool = False, max_lambda: float | None = None,
                     tries: int = DEFAULT_TRIES) -> None:
    """
    The round trip of :func:`explorer.design.round_trip` on ``bragg_mirror``: per mirror the time of
    a 5-angle design (of at most ``tries`` searches) and its median / max CIEDE2000, then the acceptance
    figures (median of the medians, share at most 1) and the median time.
    """
    from explorer.design import ranges_of, round_trip
    from explorer.materials.models import BraggMirrorModel

    material = load(BraggMirrorModel.name)
    ranges = ranges_of(material)
    draw = None if max_lambda is None else {"Lambda": (ranges["Lambda"][0], float(max_lambda))}
    rows = []

    def report(k, truth, result):
        row = {"truth": truth, "set": result.values, "median_delta_e2000": result.median_delta_e2000,
               "max_delta_e2000": float(result.delta_e2000.max()), "seconds": result.seconds,
               "cpu_seconds": result.cpu_seconds, "tries": result.tries}
        rows.append(row)
        if not as_json:
            click.echo(f"{k:3d}  {' '.join(f'{n}={v:.4g}' for n, v in truth.items())}  ->  median ΔE2000 "
                       f"{row['median_delta_e2000']:.3f}, max {row['max_delta_e2000']:.2f}, {row['seconds']:.2f} s "
                       f"({row['cpu_seconds']:.2f} s CPU{f', {result.tries} searches' if result.tries > 1 else ''})")

    round_trip(BraggMirrorModel.name, ranges, count, seed=seed, report=report, draw_ranges=draw, tries=tries)
    medians = np.array([r["median_delta_e2000"] for r in rows])
    seconds = np.array([r["seconds"] for r in rows])
    cpu = np.array([r["cpu_seconds"] for r in rows])
    summary = {"mirrors": count, "seed": seed, "max_lambda": max_lambda, "tries": tries,
               "median_of_medians": float(np.median(medians)), "share_at_most_1": float(np.mean(medians <= 1.0)),
               "median_seconds": float(np.median(seconds)), "max_seconds": float(seconds.max()),
               "median_cpu_seconds": float(np.median(cpu)), "max_cpu_seconds": float(cpu.max()),
               "load_average": list(os.getloadavg())}
    if as_json:
        click.echo(json.dumps({"summary": summary, "mirrors": rows}, indent=2))
        return
    conditions = (f"seed {seed}" + ("" if max_lambda is None else f", Lambda <= {max_lambda:g} nm")
                  + (", one search" if tries == 1 else f", up to {tries} searches"))
    click.echo(f"{count} mirrors ({conditions}): median of the "
               f"per-mirror median ΔE2000 {summary['median_of_medians']:.3f}, {100 * summary['share_at_most_1']:.0f} % at most 1; "
               f"a 5-angle design: median {summary['median_seconds']:.2f} s wall, {summary['median_cpu_seconds']:.2f} s CPU "
               f"(max {summary['max_seconds']:.2f} s, {summary['max_cpu_seconds']:.2f} s CPU; load average "
               f"{summary['load_average'][0]:.1f} on {os.cpu_count()} cores)")
