"""
``bragg-explorer albedo``: a material's directional albedo per incidence angle (:mod:`explorer.views.albedo`), and
the progress lines of the long renders. Registered by :mod:`explorer.cli.commands`.
"""

from __future__ import annotations

import contextlib
import json
import sys
import threading
import time

import click
import numpy as np

from explorer.cli.materials import PROG, load, resolve_values  # noqa: F401  (PROG: the messages)
from explorer.views.position_free import check_position_free, twin_of

DEFAULT_THETA = "0,15,30,45,60,75,85"
#: Paths per angle (albedo) of the position-free engine by default.
DEFAULT_SAMPLES = 20000


def parse_theta(text: str) -> np.ndarray:
    """``--theta``: comma-separated incidence angles in degrees, each in [0, 90)."""
    try:
        values = [float(part) for part in text.split(",") if part.strip()]
    except ValueError:
        values = []
    theta = np.asarray(values, dtype=np.float64)
    if theta.size == 0 or not np.all(np.isfinite(theta) & (theta >= 0.0) & (theta < 90.0)):
        raise click.BadParameter(f"{text!r} is not a list of angles in [0, 90) degrees (e.g. 0,30,60)", param_hint="--theta")
    return theta


#: Seconds between progress lines (and before the first: a command quicker than this prints none).
PROGRESS_INTERVAL = 2.0
#: When the last progress line was written (either kind below), so that the two never speak at once.
_last_line = [0.0]


def progress_printer(label: str, unit: str):
    """A ``progress(done, total)`` that writes a line to stderr every 2 s (and at the end after 2 s)."""
    start = last = time.perf_counter()

    def progress(done: int, total: int) -> None:
        nonlocal last
        now = time.perf_counter()
        if now - last >= PROGRESS_INTERVAL or (done == total and now - start >= PROGRESS_INTERVAL):
            last = _last_line[0] = now
            click.echo(f"{PROG}: {label}: {done}/{total} {unit} ({now - start:.0f} s)", err=True)

    return progress


@contextlib.contextmanager
def progress_while(label: str, started: bool = True):
    """
    For work that cannot count its steps (a GL render, an export): a line to stderr every 2 s while the block
    runs, unless a :func:`progress_printer` inside it spoke in the meantime. Yields ``start()``: with
    ``started=False`` the lines begin only once the block calls it, after its checks of the input, so that bad
    input found late on a loaded machine is still one line.
    """
    start = time.perf_counter()
    stop, go = threading.Event(), threading.Event()

    def begin() -> None:
        nonlocal start
        if not go.is_set():
            start = time.perf_counter()
            go.set()

    def beat() -> None:
        while not go.wait(min(0.05, PROGRESS_INTERVAL)):
            if stop.is_set():
                return
        while not stop.wait(PROGRESS_INTERVAL):
            now = time.perf_counter()
            if now - _last_line[0] >= PROGRESS_INTERVAL:
                _last_line[0] = now
                click.echo(f"{PROG}: {label}: working ({now - start:.0f} s)", err=True)

    if started:
        begin()
    thread = threading.Thread(target=beat, name="progress", daemon=True)
    thread.start()
    try:
        yield begin
    finally:
        stop.set()
        go.set()
        thread.join()


def _fail(message: str) -> None:
    click.echo(f"{PROG}: error: {message}", err=True)
    sys.exit(1)


@click.command("albedo")
@click.argument("material", type=click.Path(dir_okay=False))
@click.option("--preset", metavar="NAME", help="Start from a preset of the material (bragg-explorer presets); --set overrides it.")
@click.option("--params", "params_file", metavar="FILE", help="A parameter set (JSON or .bparam); over --preset, under --set.")
@click.option("--set", "assignments", multiple=True, metavar="NAME=VALUE", help="Set a material parameter (repeatable).")
@click.option("--theta", default=DEFAULT_THETA, show_default=True, metavar="DEG,DEG,...", help="Incidence angles in degrees (in the outer medium).")
@click.option("--engine", type=click.Choice(["gl", "numpy", "position-free"]), default="numpy", show_default=True,
              help="The GLSL BRDF on the GPU (scatter view), its numpy twin, or the position-free reference (layered Bragg stacks).")
@click.option("--samples", type=int, metavar="N", help=f"position-free: paths per angle (default {DEFAULT_SAMPLES}).")
@click.option("--seed", type=click.IntRange(min=0), default=0, show_default=True, help="position-free: the random generator's seed (>= 0).")
@click.option("--microsurface", type=click.Choice(["single", "walk"]), default="single", show_default=True,
              help="position-free: a rough layer's microfacets scatter once (Eq. 17, the model's assumption) "
                   "or every time (the random walk of Heitz et al. 2016).")
@click.option("--json", "as_json", is_flag=True, help='Print {"theta_deg": [...], "rgb": [[r, g, b], ...]} (plus "stderr" for position-free).')
def albedo_command(material, preset, params_file, assignments, theta, engine, samples, seed, microsurface, as_json):
    """Directional albedo of MATERIAL: BRDF x cos integrated over the outgoing hemisphere, plus its Dirac
    reflection (a coating's Fresnel; a smooth mirror's specular reflectance), per incidence angle.

    Linear sRGB as render writes it (a white reflector is 1, 1, 1); the light in the xz plane.
    """
    from explorer.errors import LocatedError
    from explorer.gpu import GLUnavailable
    from explorer.views import albedo as albedo_views

    try:
        angles = parse_theta(theta)
        if samples is not None and engine != "position-free":
            raise click.BadParameter("paths per angle are for --engine position-free", param_hint="--samples")
        if microsurface != "single" and engine != "position-free":
            raise click.BadParameter("the microsurface walk is for --engine position-free", param_hint="--microsurface")
        if samples is not None and samples < 1:
            raise click.BadParameter(f"{samples} is not a positive number of paths", param_hint="--samples")
        loaded = load(material)
        values = resolve_values(loaded, preset, params_file, assignments)
        stderr = None
        if engine == "gl":
            model = twin_of(loaded, values) if loaded.model else None
            from explorer.gpu import Renderer

            rgb = albedo_views.albedo_gl(loaded, values, angles, Renderer(), size=albedo_views.gl_size_for(model), model=model,
                                         progress=progress_printer("albedo", "angles"))
        else:
            from explorer.materials.brd import MaterialError

            model = twin_of(loaded, values)
            if model is None:
                raise MaterialError(loaded.path, None, "this material has no numpy twin (no known '# model:' line): use --engine gl")
            if engine == "numpy":
                rgb = albedo_views.albedo_numpy(model, angles, progress_printer("albedo", "angles"))
            else:
                check_position_free(loaded, model)
                result = albedo_views.albedo_position_free(
                    model, angles, samples or DEFAULT_SAMPLES, seed, progress_printer("position-free", "paths"), microsurface)
                rgb, stderr = result.value, result.stderr
    except (LocatedError, GLUnavailable) as error:
        _fail(str(error))
    if as_json:
        document = {"theta_deg": angles.tolist(), "rgb": rgb.tolist()}
        if stderr is not None:
            document["stderr"] = stderr.tolist()
        click.echo(json.dumps(document))
        return
    luminance = rgb @ np.array([0.2126, 0.7152, 0.0722])
    for k, t in enumerate(angles):
        line = f"theta {t:6.2f} deg: rgb {rgb[k, 0]:.6f} {rgb[k, 1]:.6f} {rgb[k, 2]:.6f}  Y {luminance[k]:.6f}"
        if stderr is not None:
            line += f"  (stderr {stderr[k, 0]:.2g} {stderr[k, 1]:.2g} {stderr[k, 2]:.2g})"
        click.echo(line)
