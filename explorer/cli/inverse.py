"""
``bragg-explorer inverse`` and ``bragg-explorer figure``: the inverse method of Bati et al. (2021) on the
command line (:mod:`explorer.physics.inverse`), registered by :mod:`explorer.cli.commands`.

A lobe is ``--lobe "R=0.9,0.7,0.5 sigma=0.03 layers=1 base=conductor"`` (keys separated by spaces or
semicolons; ``R`` one number or RGB; ``layers`` 1 or 2, default 1; ``base`` dielectric or conductor),
top first, with optional choices of its equivalence-class point (``eta``, ``tau``, ``eta_top``,
``tau_top``, ``t``; :func:`explorer.physics.inverse.invert_lobes`).
"""

from __future__ import annotations

import json
import re
import sys

import click
import numpy as np

PROG = "bragg-explorer"
CHOICE_KEYS = ("eta", "tau", "eta_top", "tau_top", "t")


def _fail(message: str) -> None:
    click.echo(f"{PROG}: error: {message}", err=True)
    sys.exit(1)


def _numbers(text: str, key: str, low: float = -np.inf, high: float = np.inf, below: bool = False):
    """One number or ``r,g,b`` in ``[low, high]`` (``[low, high)`` with ``below``), or a one-line usage error."""
    shown = text if len(text) <= 40 else text[:37] + "..."
    try:
        values = [float(v) for v in text.split(",")]
    except ValueError:
        raise click.UsageError(f"--lobe {key}={shown!r}: not a number or r,g,b") from None
    if len(values) not in (1, 3) or not all(np.isfinite(values)):
        raise click.UsageError(f"--lobe {key}={shown!r}: one number or r,g,b")
    if not all(low <= v < high if below else low <= v <= high for v in values):
        raise click.UsageError(f"--lobe {key}={shown!r}: outside the model's domain [{low:g}, {high:g}{')' if below else ']'}")
    return values[0] if len(values) == 1 else values


def parse_lobe(spec: str):
    """``(Lobe, choices)`` from one ``--lobe`` string."""
    from explorer.physics.inverse import Lobe
    from explorer.physics.lobes import VARIANCE_MAX

    shown = repr(spec if len(spec) <= 60 else spec[:57] + "...")
    fields = {}
    for part in re.split(r"[;\s]+", spec.strip()):
        if not part:
            continue
        if "=" not in part:
            raise click.UsageError(f"--lobe {shown}: expected KEY=VALUE, got {part[:40]!r}")
        key, value = part.split("=", 1)
        fields[key.strip()] = value.strip()
    unknown = set(fields) - {"R", "sigma", "layers", "base", *CHOICE_KEYS}
    if unknown:
        raise click.UsageError(f"--lobe {shown}: unknown key {sorted(unknown)[0][:20]!r} (R, sigma, layers, base, {', '.join(CHOICE_KEYS)})")
    if "R" not in fields or "sigma" not in fields:
        raise click.UsageError(f"--lobe {shown}: R and sigma are required")
    base = fields.get("base", "dielectric")
    if base not in ("dielectric", "conductor"):
        raise click.UsageError(f"--lobe {shown}: base must be dielectric or conductor")
    layers = fields.get("layers", "1")
    if layers not in ("1", "2"):
        raise click.UsageError(f"--lobe {shown}: layers must be 1 or 2")
    # The forward model's domain: energies are fractions, and a variance reaches VARIANCE_MAX at alpha = 1
    # (Belcour's f(alpha), explorer.physics.lobes), beyond which it would be silently clamped.
    sigma = _numbers(fields["sigma"], "sigma", 0.0, VARIANCE_MAX, below=True)
    if isinstance(sigma, list):
        raise click.UsageError(f"--lobe {shown}: sigma is one number")
    lobe = Lobe(_numbers(fields["R"], "R", 0.0, 1.0), sigma, int(layers), base)
    choices = {key: _numbers(fields[key], key) for key in CHOICE_KEYS if key in fields}
    return lobe, choices


def _solve(lobe_specs, tir=False):
    from explorer.physics.inverse import InverseError, forward_lobes, invert_lobes
    from explorer.physics.lobes import StackError

    if not lobe_specs:
        raise click.UsageError("give at least one --lobe")
    parsed = [parse_lobe(spec) for spec in lobe_specs]
    lobe_list = [lobe for lobe, _ in parsed]
    try:
        stack = invert_lobes(lobe_list, [choice for _, choice in parsed], tir=tir)
        energies, variances = forward_lobes(stack, [lobe.layers for lobe in lobe_list])
    except (InverseError, StackError) as error:  # a choice outside the stack's domain (eta <= 0, tau < 0, ...)
        _fail(" ".join(str(error).split()))
    return lobe_list, stack, energies, variances


@click.command("inverse")
@click.option("--lobe", "lobe_specs", multiple=True, metavar='"R=.. sigma=.. [layers=1|2] [base=..] [choices]"',
              help="A lobe at normal incidence, top first (repeatable).")
@click.option("--json", "as_json", is_flag=True, help="Print the stack, its material values and the check as JSON.")
@click.option("--tir", is_flag=True, help="Use the stack's TIR term (the layered lobes material's tir; off in Bati et al.).")
def inverse_command(lobe_specs, as_json, tir):
    """Layer stacks from BRDF lobes (Bati, Barla & Pacanowski 2021, Algorithms 1-5).

    Prints the stack (top first: eta, alpha, tau of the medium below), the --set values of
    shaders/layered_lobes.brd, and the forward model's lobes at normal incidence against the request.
    """
    from explorer.materials.lobes_model import LayeredLobesModel, values_from_stack

    lobe_list, stack, energies, variances = _solve(lobe_specs, tir)
    values = values_from_stack(stack)
    check = [
        {"requested": {"R": lobe.energy.tolist(), "sigma": lobe.variance},
         "forward": {"R": energies[k].tolist(), "sigma": variances[k].tolist()}}
        for k, lobe in enumerate(lobe_list)
    ]
    if as_json:
        click.echo(json.dumps({"stack": stack.as_dict(), "material": f"shaders/{LayeredLobesModel.name}.brd", "values": values, "lobes": check}, indent=2))
        return
    for i, layer in enumerate(stack.as_dict()["interfaces"], start=1):
        click.echo(f"interface {i}: " + ", ".join(f"{k} = {v}" for k, v in layer.items()))
    for k, entry in enumerate(check, start=1):
        click.echo(f"lobe {k}: requested R = {np.round(entry['requested']['R'], 5).tolist()}, sigma = {entry['requested']['sigma']:g}; "
                   f"forward R = {np.round(entry['forward']['R'], 5).tolist()}, sigma = {np.round(entry['forward']['sigma'], 5).tolist()}")
    sets = " ".join(f"--set {k}={','.join(f'{x:.6g}' for x in np.atleast_1d(v))}" for k, v in values.items())
    from explorer.cli.materials import command_prefix

    click.echo(f"render: {command_prefix()} render {LayeredLobesModel.name} {sets} --view env --out lobes.png")


@click.command("figure")
@click.option("--lobe", "lobe_spec", required=True, metavar='"R=.. sigma=.. [layers=1|2] [base=..]"', help="One lobe (in air).")
@click.option("--out", required=True, type=click.Path(dir_okay=False), help="The PNG to write.")
@click.option("--samples", type=click.IntRange(8, 400), default=96, show_default=True, help="Grid samples per axis.")
def figure_command(lobe_spec, out, samples):
    """Plot a lobe's equivalence class (Bati et al., Figs. 4, 7, 9, 12) to a PNG.

    1-layer conductor: kappa(eta) per channel, valid between Eqs. 10 and 9. 1-layer dielectric: the
    roots of Eq. 7 against the ambient index. 2-layer: the (eta_1, eta_2) plane, each channel's valid
    region (tau_1 >= 0, sigma_12 >= 0), their intersection and tau_1 isolines; invalid regions hatched.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from explorer.bench import FIGURE_SUFFIXES, save_figure
    from explorer.files import OutputError, check_output
    from explorer.physics.inverse import one_layer_class, two_layer_class

    try:
        check_output(out, FIGURE_SUFFIXES)
    except OutputError as error:
        _fail(str(error))
    lobe, _ = parse_lobe(lobe_spec)
    colours = ("tab:red", "tab:green", "tab:blue")
    fig, ax = plt.subplots(figsize=(5.5, 4.5), dpi=110)
    if lobe.layers == 2:
        cls = two_layer_class(lobe.energy, lobe.variance, samples=samples)
        E1, E2 = np.meshgrid(cls.eta_1, cls.eta_2, indexing="ij")
        ax.contourf(E1, E2, (~cls.valid).astype(float), levels=[0.5, 1.5], colors="none", hatches=["//"])
        for ch in range(3):
            ax.contourf(E1, E2, cls.valid_channel[..., ch].astype(float), levels=[0.5, 1.5], colors=[colours[ch]], alpha=0.15)
            tau = np.where(np.isfinite(cls.tau_1[..., ch]), cls.tau_1[..., ch], np.nan)
            if np.isfinite(tau).any() and np.nanmax(tau) > 0:
                ax.contour(E1, E2, tau, levels=[0.0, 0.25, 0.5, 1.0], colors=[colours[ch]], linewidths=0.8)
        if cls.valid.any():
            ax.contour(E1, E2, cls.valid.astype(float), levels=[0.5], colors="k", linewidths=1.5)
        ax.set_xlabel("η₁")
        ax.set_ylabel("η₂")
        ax.set_title(f"2-layer class: R = {np.round(lobe.energy, 3).tolist()}, σ = {lobe.variance:g}\n"
                     f"grey/black: all channels valid; lines: τ₁ isolines 0, .25, .5, 1", fontsize=9)
    elif lobe.base == "conductor":
        cls = one_layer_class(lobe.energy, lobe.variance, base="conductor", samples=samples)
        for ch in range(3):
            eta, kappa, valid = cls.eta[:, ch], cls.kappa[:, ch], cls.valid[:, ch]
            ax.plot(eta, kappa, "--", color=colours[ch], linewidth=0.8)
            ax.plot(np.where(valid, eta, np.nan), np.where(valid, kappa, np.nan), color=colours[ch], linewidth=2)
        ax.set_xlabel("η₁")
        ax.set_ylabel("κ₁")
        ax.set_title(f"1-layer conductor class: R = {np.round(lobe.energy, 3).tolist()}, σ = {lobe.variance:g}\n"
                     "solid: η between Eqs. 10 and 9 (κ ≥ η)", fontsize=9)
    else:
        eta_0 = np.linspace(1.0, 4.0, samples)
        lower, upper = np.array([one_layer_class(lobe.energy, lobe.variance, eta_0=e).eta for e in eta_0]).T
        ax.plot(eta_0, upper, "k", label="upper root")
        ax.plot(eta_0, np.where(lower >= 1.0, lower, np.nan), "k--", label="lower root (η₁ ≥ 1)")
        ax.axhspan(0.0, 1.0, hatch="//", fill=False, linewidth=0)
        ax.axhspan(4.0, 16.0, hatch="//", fill=False, linewidth=0)
        ax.set_ylim(0.5, 6.0)
        ax.set_xlabel("η₀ (the medium above)")
        ax.set_ylabel("η₁")
        ax.legend(fontsize=8)
        ax.set_title(f"1-layer dielectric class: R = {lobe.energy.max():.3g}, σ = {lobe.variance:g}", fontsize=9)
    fig.tight_layout()
    try:
        save_figure(fig, out)
    except OutputError as error:
        _fail(str(error))
    finally:
        plt.close(fig)
    click.echo(f"wrote {out}")
