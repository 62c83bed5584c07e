"""
``bragg-explorer``: render materials headless, inspect material files, benchmark the methods.

A material argument is a file, or the name of a built-in material (``bragg_mirror``; see
:mod:`explorer.resources`). Bad input (a malformed material file, an unknown or out-of-range ``--set``,
a GLSL error, an unwritable ``--out``, no GL) ends with one line on stderr naming the file and line where
there is one, and a non-zero exit; an output file is either complete or not written at all.
"""

from __future__ import annotations

import json
import os
import sys
from pathlib import Path

import click
import numpy as np

from explorer.materials.brd import round_integer
from explorer.errors import LocatedError
from explorer.views.images import OutputError, check_output, write_image
from explorer.resources import DEFAULT_MATERIAL, display_path, package_version
from explorer.views.geometry import DEFAULT_LIGHT, VIEWS, view_named

from explorer.cli.design import DEFAULT_TRIES, MAX_TRIES
from explorer.cli.materials import PROG, SuggestingChoice, command_prefix, resolve_values, warn
from explorer.cli.materials import load as _load
#: The largest ``--size`` side parsed at all; each engine then checks its own limits.
MAX_SIZE = 1 << 16


#: Set (to 1) for an unexpected error's traceback, as ``--debug`` does.
DEBUG_ENV = "BRAGG_EXPLORER_DEBUG"


def _debug(argv: list[str]) -> bool:
    """``--debug`` anywhere on the command line, or :data:`DEBUG_ENV` set (not to 0)."""
    return "--debug" in argv or os.environ.get(DEBUG_ENV, "").strip() not in ("", "0")


def _terminate(signum, _frame) -> None:
    """SIGTERM as ``SystemExit``: outputs being written (:func:`explorer.files.atomic_output`) are cleaned up."""
    raise SystemExit(128 + signum)


def _fail(message: str) -> None:
    click.echo(f"{PROG}: error: {message}", err=True)
    sys.exit(1)


def parse_size(text: str | None, view: str) -> tuple[int, int]:
    """``W`` or ``WxH`` (a square for ``W`` alone, except the gradient, which keeps its height)."""
    from explorer.views.geometry import view_named

    default_size = view_named(view).default_size
    if text is None:
        return default_size
    parts = text.lower().split("x")
    try:
        numbers = [int(p) for p in parts]
    except ValueError:
        numbers = []
    # A sanity bound only: the GL engine checks the context's own limits (explorer.gpu.GLLimits).
    if len(numbers) not in (1, 2) or min(numbers) < 1 or max(numbers) > MAX_SIZE:
        raise click.BadParameter(f"{text[:40]!r} is not W or WxH with sizes in 1..{MAX_SIZE}", param_hint="--size")
    if len(numbers) == 1:
        return (numbers[0], numbers[0] if view_named(view).square else default_size[1])
    return numbers[0], numbers[1]


def parse_light(text: str | None, view: str) -> tuple[float, float] | None:
    """``THETA,PHI`` in degrees (theta in [0, 180] from +z, phi from +x; theta <= 90 for ``scatter``)."""
    from explorer.views.geometry import LIGHT_VIEWS, view_named

    if text is None:
        return None
    top = view_named(view).light_theta_max
    if top is None:
        raise click.BadParameter(f"the {view} view has no light (--light is for {', '.join(LIGHT_VIEWS)})", param_hint="--light")
    try:
        theta, phi = (float(part) for part in text.split(","))
    except ValueError:
        raise click.BadParameter(f"{text!r} is not THETA,PHI in degrees (e.g. 30,0)", param_hint="--light") from None
    if not (np.isfinite(theta) and np.isfinite(phi)) or not 0.0 <= theta <= top:
        raise click.BadParameter(f"{text!r}: THETA must be in [0, {top:g}] and PHI finite", param_hint="--light")
    return theta, phi


def parse_exposure(text: str | None, out: Path) -> float | None:
    """
    ``--exposure``: a positive multiplier of the linear values before the PNG's sRGB encode, or ``auto``
    (None: :func:`explorer.views.exposure.auto_exposure` of the image).
    """
    if text is None:
        return 1.0
    if text.strip().lower() == "auto":
        exposure = None
    else:
        try:
            exposure = float(text)
        except ValueError:
            exposure = float("nan")
        if not (np.isfinite(exposure) and exposure > 0.0):
            raise click.BadParameter(f"{text!r} is not a positive multiplier (e.g. 2 for one stop brighter) or auto",
                                     param_hint="--exposure")
    if out.suffix.lower() != ".png":
        raise click.BadParameter(f"scales the 8-bit .png encode; {out.suffix or 'this output'} keeps the linear values",
                                 param_hint="--exposure")
    return exposure


def saved_view(params_file: str | None, ctx: click.Context) -> dict:
    """
    What ``--params FILE`` saved of the app's view (:func:`explorer.app.parameter_files.check_view`), as
    ``render``'s own options: ``view``, ``exposure`` (a string, as typed), ``tonemap``, ``fill``, ``environment``, ``env_rotation`` and ``light``
    (``(theta, phi)``: the app's light turned by its orbit camera into view space). Only for the options
    the command line leaves unset; ``{}`` without a file or a saved view.
    """
    if params_file is None:
        return {}
    from explorer.app.parameter_files import load_view

    view = load_view(params_file) or {}
    given = {name for name in ("view", "light", "exposure", "env_file", "env_rotation", "tonemap", "fill")
             if ctx.get_parameter_source(name) == click.core.ParameterSource.COMMANDLINE}
    result: dict = {}
    if "view" in view and "view" not in given:
        result["view"] = view["view"]
    if "exposure" in view and "exposure" not in given:
        result["exposure"] = repr(view["exposure"])
    if "tonemap" in view and "tonemap" not in given:
        result["tonemap"] = view["tonemap"]
    if "fill" in view and "fill" not in given and result.get("view", "lit") == "lit":
        result["fill"] = view["fill"]
    if "environment" in view and "env_file" not in given and result.get("view") in ("env", "lit"):  # lit: a smooth mirror's
        result["environment"] = view["environment"]
    if "env_rotation" in view and "env_rotation" not in given and result.get("view") in ("env", "lit"):
        result["env_rotation"] = view["env_rotation"]
    if ("light" in view or "camera" in view) and "light" not in given:
        from explorer.app.camera import light_vector
        from explorer.views.geometry import DEFAULT_LIGHT

        x, y, z = (float(c) for c in light_vector(view.get("light", DEFAULT_LIGHT), view.get("camera", (0.0, 0.0))))
        result["light"] = (float(np.degrees(np.arccos(np.clip(z, -1.0, 1.0)))), float(np.degrees(np.arctan2(y, x))))
    return result


def parse_plot(view: str, **options):
    """
    The plot views' settings (:class:`explorer.views.plots.PlotSettings`) from the options given (None: not
    given), or None for the other views; an option a view does not take is a one-line usage error.
    """
    from explorer.views.geometry import PLOT_VIEWS
    from explorer.views.plots import PLOT_SETTINGS, PlotSettings

    given = {name: value for name, value in options.items() if value not in (None, False)}
    if view not in PLOT_VIEWS:
        if given:
            flags = ", ".join(f"--{name.replace('_', '-')}" for name in given)
            raise click.BadParameter(f"{flags}: for the plot views ({', '.join(PLOT_VIEWS)})", param_hint="--view")
        return None
    for name in ("theta_d", "theta_h", "phi_v"):
        if name in given and name not in PLOT_SETTINGS[view]:
            takes = [v for v, settings in PLOT_SETTINGS.items() if name in settings]
            raise click.BadParameter(f"--{name.replace('_', '-')} is for the {', '.join(takes)} plot, not {view}", param_hint="--view")
    try:
        return PlotSettings(**given)
    except ValueError as error:
        raise click.BadParameter(str(error), param_hint="--view") from None


def _write_plot(loaded, view: str, image, plot, out: Path, light, engine: str) -> None:
    """A plot view's chart or values (:mod:`explorer.views.plot_images`), the values as :func:`explorer.views.plots.plotted` has them."""
    from explorer.views.geometry import light_direction
    from explorer.views.plot_images import write_plot
    from explorer.views.plots import cos_light, plotted

    height, width = image.shape[:2]
    values = plotted(image, plot, cos_light(view, width, height, light_direction(light), plot))
    shown_light = (light or DEFAULT_LIGHT) if view_named(view).takes_light else None
    from explorer.views.mirror import is_mirror_only

    write_plot(view, values, plot, out, f"{display_path(loaded.path)}: {view} ({engine})", shown_light, is_mirror_only(loaded))
    click.echo(f"wrote {out} ({view} plot, {width}x{height} samples, {engine})")


def summary(command: click.Command) -> str:
    """A command's line in ``--help``: its ``short_help``, or its docstring's whole first paragraph."""
    if command.short_help:
        return command.short_help
    paragraph = (command.help or "").strip().split("\n\n")[0]
    return " ".join(paragraph.split())


class FullSummaryGroup(click.Group):
    """
    A group whose command list shows each command's whole summary (:func:`summary`), wrapped: click's
    own cuts it at about 45 characters or at the first full stop ("Bati et al., Figs.").
    """

    def format_commands(self, ctx: click.Context, formatter: click.HelpFormatter) -> None:
        rows = [(name, summary(command)) for name in self.list_commands(ctx)
                if (command := self.get_command(ctx, name)) is not None and not command.hidden]
        if rows:
            with formatter.section("Commands"):
                formatter.write_dl(rows)


@click.group(cls=FullSummaryGroup, invoke_without_command=True, context_settings={"help_option_names": ["-h", "--help"]})
@click.option("--debug", is_flag=True, help=f"Print the traceback of an unexpected error (a bug); also {DEBUG_ENV}=1.")
@click.version_option(package_version(), "--version", prog_name=PROG, message="%(prog)s %(version)s")
@click.pass_context
def cli(ctx: click.Context, debug: bool) -> None:  # debug: read by main() before click parses
    """Real-time explorer of iridescent materials (Bragg mirrors, thin films).

    Without a command: open the explorer on the default Bragg mirror when a display exists; without
    one, say so and render it (sphere and angular gradient) to out/.

    From a source checkout, python3 -m explorer test [PYTEST ARGS] runs the test suite (pytest, with
    Xvfb for the app's scripted sessions).
    """
    if ctx.invoked_subcommand is None:
        from explorer.app import display_available

        if display_available():
            ctx.invoke(open_material, materials=(str(DEFAULT_MATERIAL),), preset=None, script=None, report=None, window_size=None)
            return
        click.echo(f"{PROG}: no display (DISPLAY is not set or cannot be opened): writing the headless render of the default view to out/", err=True)
        ctx.invoke(default_job)


@cli.command("open")
@click.argument("materials", nargs=-1, type=click.Path(dir_okay=False))
@click.option("--preset", metavar="NAME", help="Start from a preset of the material (bragg-explorer presets).")
@click.option("--script", type=click.Path(dir_okay=False), metavar="FILE.json",
              help="Play a scripted session (a JSON list of actions, docs/app.md), then close: screenshots, tests, bench --app.")
@click.option("--report", type=click.Path(dir_okay=False), metavar="FILE.json", help="Write the session's JSON report (frame times, values).")
@click.option("--window-size", metavar="WxH", help="Window size in pixels (default 1280x800).")
@click.option("--maps", "maps_dir", metavar="DIR", help="Structure maps (design --target-image --out-maps DIR) drawn on the mirror "
              "in the Texture window, each map shown there; MATERIAL defaults to the one the folder names.")
def open_material(materials, preset, script, report, window_size, maps_dir):
    """Open the interactive explorer on MATERIALS (.brd, BRDF Explorer's .brdf, or built-ins' names; none:
    the default Bragg mirror).

    Several materials are listed in the Materials window, each with its colour; the plots overlay the
    visible ones and the sphere shows the chosen one (the first; --preset applies to it).
    """
    from explorer.app import DEFAULT_WINDOW, AppError, display_available, run_app
    from explorer.gpu import GLUnavailable

    try:
        if maps_dir is not None and not materials:
            from explorer.views.maps import maps_material

            materials = (maps_material(maps_dir),)
        materials = materials or (str(DEFAULT_MATERIAL),)
        loaded = _load(materials[0])
        if maps_dir is not None:  # a bad folder: one line before any window
            from explorer.views.surface_texture import MapTexture

            MapTexture.from_folder(maps_dir, loaded, loaded.resolve({}))
        more = [_load(other).path for other in materials[1:]]
        if preset is not None:
            from explorer.materials.presets import presets_for

            presets_for(loaded.path).get(preset)
        actions = None
        if script is not None:
            try:
                actions = json.loads(Path(script).read_text(encoding="utf-8"))
            except (OSError, ValueError) as error:
                raise click.BadParameter(f"{script}: {error}", param_hint="--script") from None
        size = DEFAULT_WINDOW
        if window_size is not None:
            try:
                size = tuple(int(v) for v in window_size.lower().split("x"))
                assert len(size) == 2 and min(size) >= 200
            except (ValueError, AssertionError):
                raise click.BadParameter(f"{window_size!r} is not WxH (at least 200x200)", param_hint="--window-size") from None
        if not display_available():
            raise AppError("no display: the explorer needs a window (set DISPLAY, or run under xvfb-run); "
                           f"for images without a window use: {command_prefix()} render")
        status = run_app(loaded.path, preset, script=actions, report=report, window_size=size,
                         is_default=Path(loaded.path).resolve() == DEFAULT_MATERIAL.resolve(), more_paths=more, maps=maps_dir)
    except ImportError as error:
        _fail(f"the explorer needs imgui-bundle and PyOpenGL ({error}); run: python3 -m explorer")
    except (LocatedError, GLUnavailable, OutputError, AppError) as error:
        _fail(str(error))
    sys.exit(status)


def _errors(function):
    """Turn the expected failures of bad input into one line and exit status 1."""
    import functools

    from explorer.gpu import GLUnavailable

    @functools.wraps(function)
    def wrapper(*args, **kwargs):
        try:
            return function(*args, **kwargs)
        except (LocatedError, GLUnavailable, OutputError) as error:
            _fail(str(error))

    return wrapper


@cli.command()
@click.argument("material", type=click.Path(dir_okay=False), required=False)
@click.option("--view", type=SuggestingChoice(list(VIEWS)), default="sphere", show_default=True)
@click.option("--set", "assignments", multiple=True, metavar="NAME=VALUE", help="Set a material parameter (repeatable).")
@click.option("--size", metavar="W[xH]", help="Image size in pixels (default 256x256; gradient 256x32).")
@click.option("--out", required=True, type=click.Path(), help="FILE.png (8-bit sRGB), FILE.npy or FILE.exr (linear float32 RGB).")
@click.option("--engine", type=click.Choice(["gl", "numpy", "position-free", "mitsuba"]), default="gl", show_default=True,
              help="The GPU shader, its numpy twin, (layered Bragg stacks, lit and slice) the position-free reference, or (env view) Mitsuba 3 with the explorer's BSDF plugins.")
@click.option("--light", metavar="THETA,PHI", help="Light direction in degrees for lit, scatter and textured (default 45,0).")
@click.option("--preset", metavar="NAME", help="Start from a preset of the material (bragg-explorer presets); --set overrides it.")
@click.option("--params", "params_file", metavar="FILE", help="A parameter set (JSON, or BRDF Explorer's .bparam, as the app's Files tab saves); over --preset, under --set.")
@click.option("--exposure", metavar="X", help="PNG only: multiply the linear values by X before the 8-bit sRGB encode (the app's exposure; 2 = one stop brighter), or auto: the bright end of the object to white.")
@click.option("--tonemap", type=click.Choice(["none", "agx", "aces"]),
              help="PNG only: the display curve after the exposure: agx (Sobotka's AgX, Blender's default; the default of the lit, env and textured views: vivid colours and highlights roll off to white), aces (Narkowicz's ACES fit), none (clamp; the default of the colour views and plots). .npy and .exr stay linear.")
@click.option("--fill", type=click.FloatRange(min=0.0), metavar="X",
              help="lit view: the radiance of a uniform white environment beside the point light (default 0.15; 0: the light alone). A smooth mirror reflects --env instead.")
@click.option("--texture", metavar="FILE", help="textured and env views: grey image of a film's D_inc or a mirror's T (default shaders/textures/thickness_noise.png; env: none).")
@click.option("--dinc-range", metavar="MIN,MAX", help="textured view: D_inc (nm) at black and white (default 0,1125).")
@click.option("--prefilter", type=click.Choice(["on", "off"]), default="off", show_default=True, help="textured view: Section 5's prefiltering (methods 1-3).")
@click.option("--env", "env_file", metavar="FILE|NAME", help="env view (and lit: what a smooth mirror reflects): equirectangular .hdr or .exr (default shaders/environments/default.hdr), or sky, studio, 'white furnace'.")
@click.option("--spp", type=click.IntRange(min=1), help="env view, or --engine position-free: Monte Carlo samples per pixel (default 64).")
@click.option("--variant", help="--engine mitsuba: llvm_ad_rgb (default), llvm_ad_spectral, scalar_rgb or scalar_spectral.")
@click.option("--mesh", metavar="FILE.obj|teapot|cube|torus", help="lit, textured and env views: this mesh instead of the sphere (an OBJ file, or a generated shape; a texture or --maps by its texture coordinates).")
@click.option("--env-rotation", "env_rotation", type=float, metavar="DEGREES", help="env and lit views: the environment turned about the vertical.")
@click.option("--background", is_flag=True, help="env view: the environment drawn behind the object (else black).")
@click.option("--mapping", type=click.Choice(["both", "lambda", "delta", "none"]),
              help="textured view of a Bragg mirror: which of Lambda (0.5 + 0.5 T) and delta^T follow the texture T (default both; supplemental Fig. 7).")
@click.option("--theta-d", "theta_d", type=float, help="theta_h plot: the difference angle theta_d in degrees (default 0).")
@click.option("--theta-h", "theta_h", type=float, help="theta_d plot: the half-vector angle theta_h in degrees (default 0).")
@click.option("--phi-v", "phi_v", type=float, help="theta_v plot: the view's azimuth phi_v in degrees (default 0).")
@click.option("--log", "log_scale", is_flag=True, help="Plots: log10(1 + x).")
@click.option("--channel", type=click.Choice(["rgb", "r", "g", "b", "luminance"]), help="Plots: the channel plotted (default rgb, all three).")
@click.option("--ndotl", is_flag=True, help="Plots: times N.L (the albedo plot: times cos theta_i).")
@click.option("--maps", "maps_dir", metavar="DIR", help="textured (lit) and env views: the structure maps design --target-image wrote, "
              "each texel its own mirror on the sphere; with --theta (--engine numpy): one pixel a texel, its colour at that angle.")
@click.option("--theta", "maps_theta", type=float, help="--maps: the flat image of the maps' colours at this viewing angle in degrees "
              "(--engine numpy: converged spectral colours; gl: by the material's method).")
@_errors
def render(material, view, assignments, size, out, engine, light, preset, params_file, exposure, tonemap, fill, texture, dinc_range,
           prefilter, env_file, spp, variant, mesh, env_rotation, background, theta_d, theta_h, phi_v, log_scale, channel,
           ndotl, mapping, maps_dir, maps_theta):
    """Render MATERIAL (.brd, BRDF Explorer .brdf, or a built-in's name such as bragg_mirror) headless
    to a PNG, .npy or .exr. Without MATERIAL, the one --params names.

    Views: gradient and sphere show a material's reflectance(cos_theta); lit (a sphere under one
    directional light), slice (BRDF Explorer's image slice, theta_h across, theta_d down) and scatter
    (scatterogram, circles at 5, 30, 60 and 90 degrees in the PNG only) call its BRDF(L, V, N, X, Y);
    textured is the lit sphere of a thin film whose D_inc comes from --texture over --dinc-range, or of a
    Bragg mirror whose Lambda and/or delta follow it (--mapping);
    env is the sphere under an environment map (--env), a Monte Carlo mean of --spp samples per pixel
    (--engine numpy: the exact integral, slow; use a small --size). BRDF Explorer's plots: theta_v (with
    --phi-v), theta_h (with --theta-d), theta_d (with --theta-h), lobe3d (the lobe for --light) and albedo,
    as a chart (.png) or their values (.npy); --size W sets their samples.
    """
    if maps_dir is not None and maps_theta is not None:
        from explorer.cli.paint import render_maps_command

        render_maps_command(material, maps_dir, view, maps_theta, out, engine, exposure, assignments)
        return
    if maps_theta is not None:
        raise click.UsageError("--theta goes with --maps")
    if maps_dir is not None:
        from explorer.views.maps import maps_material

        if click.get_current_context().get_parameter_source("view") == click.core.ParameterSource.DEFAULT:
            view = "textured"  # the maps on the lit sphere
        if view not in ("textured", "lit", "env"):
            raise click.BadParameter(f"the maps are drawn in the textured (lit sphere) and env views, not {view}", param_hint="--maps")
        if texture is not None or mapping is not None or dinc_range is not None or prefilter == "on":
            raise click.BadParameter("the maps give the structure of every texel: no --texture, --mapping, --dinc-range or --prefilter",
                                     param_hint="--maps")
        material = material or maps_material(maps_dir)
        view = "textured" if view == "lit" else view  # the textured view is the lit sphere with its surface
    from explorer.views.geometry import scatter_circles, view_named

    if material is None:
        if params_file is None:
            raise click.UsageError("Missing argument 'MATERIAL' (or a --params file that names one).")
        from explorer.app.parameter_files import named_material

        material = named_material(params_file)
        if material is None:
            raise click.UsageError(f"--params {params_file} names no material: give MATERIAL")
    check_output(Path(out))
    saved = saved_view(params_file, click.get_current_context())  # the app's view saved with the parameters
    view, exposure, env_file = saved.get("view", view), saved.get("exposure", exposure), saved.get("environment", env_file)
    env_rotation, tonemap, fill = saved.get("env_rotation", env_rotation), saved.get("tonemap", tonemap), saved.get("fill", fill)
    exposure_factor = parse_exposure(exposure if Path(out).suffix.lower() == ".png" or "exposure" not in saved else None, Path(out))
    light_angles = parse_light(light, view) if light is not None or "light" not in saved or not view_named(view).takes_light else saved["light"]
    loaded = _load(material)
    from explorer.materials.methods import method_labels

    values = resolve_values(loaded, preset, params_file, assignments)  # as the app opens it
    width, height = parse_size(size, view)
    plot = parse_plot(view, theta_d=theta_d, theta_h=theta_h, phi_v=phi_v, log=log_scale, channel=channel, ndotl=ndotl)
    if plot is not None and Path(out).suffix.lower() not in (".png", ".npy"):
        raise click.BadParameter("a plot is a chart (.png) or its values (.npy)", param_hint="--out")
    if plot is not None and exposure is not None:
        raise click.BadParameter("a plot's values are not exposed (use --log)", param_hint="--exposure")
    if plot is not None and tonemap is not None:
        raise click.BadParameter("a plot's values are not tone mapped (use --log)", param_hint="--tonemap")
    from explorer.views.tonemap import default_tonemap

    tonemap = tonemap or default_tonemap(view)
    if fill is not None and view != "lit":
        raise click.BadParameter("the environment fill is the lit view's", param_hint="--fill")
    thickness = None
    surface_given = texture is not None or dinc_range is not None or mapping is not None
    if maps_dir is not None:
        from explorer.views.surface_texture import MapTexture

        thickness, values = MapTexture.from_folder(maps_dir, loaded, values)
    elif view == "textured" or (view == "env" and surface_given):
        from explorer.views.surface_texture import BraggTexture, check_texture_kind
        from explorer.views.thickness import DEFAULT_TEXTURE, ThicknessTexture, parse_dinc_range

        if view == "env" and prefilter == "on":
            raise click.BadParameter("prefiltering is the textured view's (the env view reads the texture unfiltered)", param_hint="--prefilter")

        if check_texture_kind(loaded) == "bragg":
            if dinc_range is not None or prefilter == "on":
                raise click.BadParameter("a Bragg mirror's texture maps Lambda and delta (--mapping), not D_inc", param_hint="--dinc-range/--prefilter")
            thickness = BraggTexture.from_file(texture if texture is not None else DEFAULT_TEXTURE, mapping or "both")
        else:
            if mapping is not None:
                raise click.BadParameter(f"--mapping is a Bragg mirror's; {display_path(loaded.path)}'s texture is its D_inc (--dinc-range)",
                                         param_hint="--mapping")
            thickness = ThicknessTexture.from_file(
                texture if texture is not None else DEFAULT_TEXTURE, parse_dinc_range(dinc_range), prefilter == "on"
            )
    elif texture is not None or dinc_range is not None or prefilter == "on" or mapping is not None:
        raise click.BadParameter("--texture, --dinc-range, --prefilter and --mapping are for the textured and env views", param_hint="--view")
    environment = None
    from explorer.views.mirror import is_mirror_only

    mirror_lit = view == "lit" and is_mirror_only(loaded) and (env_file is not None or env_rotation is not None) and not background
    if view == "env" or (mirror_lit and (spp is None or engine == "position-free")):  # lit: what a smooth mirror reflects
        from explorer.views.env import DEFAULT_ENVIRONMENT, environment_named

        environment = environment_named(env_file if env_file is not None else DEFAULT_ENVIRONMENT)
        if (env_rotation is not None or background) and engine == "mitsuba":
            raise click.BadParameter("--env-rotation and --background are for the gl and numpy engines", param_hint="--engine")
        if env_rotation is not None:
            environment = environment.rotated(env_rotation)
    elif env_file is not None or (spp is not None and engine != "position-free") or env_rotation is not None or background:
        raise click.BadParameter("--env, --spp, --env-rotation and --background are for the env view (--env and --env-rotation "
                                 "also for a smooth mirror's lit view)", param_hint="--view")
    mesh_shape = None
    if mesh is not None:
        from explorer.views.mesh import mesh_named

        if view not in ("lit", "env", "textured") or engine not in ("gl", "numpy"):
            raise click.BadParameter(f"a mesh is drawn in the lit, textured and env views by the gl and numpy engines, not {view} ({engine})",
                                     param_hint="--mesh")
        mesh_shape = mesh_named(mesh)
    if engine == "mitsuba" or variant is not None:
        from explorer.cli.export import check_mitsuba_render

        check_mitsuba_render(view, engine, variant)
    if engine == "position-free":
        from explorer.views.position_free import POSITION_FREE_VIEWS

        if view not in POSITION_FREE_VIEWS:
            raise click.BadParameter(f"the position-free engine renders the {' and '.join(POSITION_FREE_VIEWS)} views", param_hint="--view")
        fill = 0.0
    else:
        from explorer.views.fill import DEFAULT_FILL, has_fill

        fill = (DEFAULT_FILL if fill is None else fill) if view == "lit" and has_fill(loaded) else 0.0
    from explorer.cli.albedo import progress_printer, progress_while
    from explorer.rendering import render_material

    with progress_while(f"render {view} ({engine})", started=False) as checked:
        image = render_material(loaded, values, view, width, height, engine, light_angles, thickness, environment, spp,
                                variant=variant, mesh=mesh_shape, background=background, plot=plot, fill=fill,
                                progress_printer=progress_printer, warn=warn, checked=checked)
    if plot is not None:
        _write_plot(loaded, view, image, plot, Path(out), light_angles, engine)
        return
    circles = scatter_circles(width, height) if view_named(view).circles else None
    if exposure_factor is None:  # --exposure auto
        from explorer.views.exposure import auto_exposure

        exposure_factor = auto_exposure(image, tonemap)
        click.echo(f"{PROG}: exposure auto: {exposure_factor:.3g}", err=True)
    write_image(image, Path(out), circles, exposure_factor, tonemap)
    bad = int((~np.isfinite(image)).sum())
    method = method_labels(loaded).get(round_integer(values["method"])) if "method" in values else None
    what = ", ".join([f"{width}x{height}", view, engine] + ([f"method {method}"] if method else []))
    if maps_dir is not None:
        h, w = thickness.index.shape
        chosen = round_integer(values["method"]) if "method" in values else None
        texel = None if chosen is None else thickness.declaration.texel_method(chosen)  # a table's method: its stand-in
        stand_in = method_labels(loaded).get(texel) if texel != chosen else None
        what += f"; {', '.join(thickness.maps)} from {w}x{h} maps" + (f", method {stand_in} per texel" if stand_in else "")
    click.echo(f"wrote {out} ({what})" + (f"; {bad} non-finite values!" if bad else ""))
    from explorer.cli.accuracy import accuracy_note

    note = accuracy_note(loaded, values)  # the chosen Bragg method off by more than ΔE2000 2 here: which one is not
    if note:
        click.echo(f"{PROG}: note: {note}", err=True)


@cli.command()
@click.argument("material", type=click.Path(dir_okay=False), required=False)
@click.option("--json", "as_json", is_flag=True, help="Print the parameters as JSON.")
@click.option("--dispersions", is_flag=True, help="List the media an index may name (n2=chitin), with formula and citation.")
@_errors
def info(material, as_json, dispersions):
    """Print the parameters of MATERIAL (a file, or a built-in's name such as thin_film), or --dispersions."""
    from explorer.materials.methods import method_labels, opening_values
    from explorer.materials.twins import capabilities_of

    if dispersions:
        from explorer.cli.spectrum import dispersions_listing

        click.echo(dispersions_listing(as_json))
        return
    if material is None:
        raise click.UsageError("info needs MATERIAL (or --dispersions)")
    loaded = _load(material)
    labels = method_labels(loaded)
    opening = opening_values(loaded).get("method")
    if as_json:
        document = loaded.info()
        for shown in document["parameters"]:
            if shown["type"] == "int":  # a count or a switch: 20, not 20.0
                shown.update({key: round_integer(shown[key]) for key in ("min", "max", "default")})
        if labels:
            document["methods"] = {str(value): label.partition(" ")[2] for value, label in labels.items()}
        document["capabilities"] = capabilities_of(loaded).as_json()  # the twin's declaration, from the registry
        click.echo(json.dumps(document, indent=2))
        return
    click.echo(f"{display_path(loaded.path)}: model {loaded.model or '(none)'}, {len(loaded.parameters)} parameters")
    width = max((len(p.name) for p in loaded.parameters), default=0)
    for p in loaded.parameters:
        shown = p.info()
        if p.type == "int":  # a count or a switch: 20, not 20.0
            shown.update({key: round_integer(shown[key]) for key in ("min", "max", "default")})
        default = labels.get(shown["default"], shown["default"]) if p.name == "method" else shown["default"]
        bounds = "" if p.min is None else f" in [{shown['min']:g}, {shown['max']:g}]"
        opens = (f" (every command and the app open it on {labels.get(opening, opening)})"
                 if p.name == "method" and opening is not None and opening != shown["default"] else "")
        unit = f" {p.unit}" if p.unit and p.unit != "1" else ""
        click.echo(f"  {p.type:5} {p.name:{width}} default {default}{bounds}{unit}{opens}")
        if p.doc:
            click.echo(f"  {'':5} {'':{width}} {p.doc}")
        if p.name == "method" and labels:
            click.echo(f"  {'':5} {'':{width}} methods: {', '.join(labels.values())}")
    click.echo(f"  supports: {capabilities_of(loaded).summary()}")


@cli.command()
@click.argument("material", required=False)
@click.option("--json", "as_json", is_flag=True, help="Print the presets as JSON.")
@_errors
def presets(material, as_json):
    """List the presets (name, material, description) of MATERIAL (a file, or a built-in's name such as
    thin_film), or of every built-in material that has some."""
    from explorer.materials.presets import all_preset_files, load_presets, presets_path

    if material:
        loaded = _load(material)
        path = presets_path(loaded.path)
        files = [load_presets(path)] if path.is_file() else []
        none = f"{display_path(loaded.path)}: no presets (they would be in {display_path(path)})"
    else:
        files = all_preset_files()
        none = "no presets installed"
    rows = [
        {"name": p.name, "material": display_path(p.material.path), "figure": p.figure,
         "description": p.description, "values": p.values, **({"citation": p.citation} if p.citation else {})}
        for f in files for p in f.presets.values()
    ]
    if as_json:
        click.echo(json.dumps(rows, indent=2))
        return
    if not rows:
        click.echo(none)
        return
    width = max((len(r["name"]) for r in rows), default=4)
    material_width = max((len(r["material"]) for r in rows), default=8)
    for r in rows:
        click.echo(f"{r['name']:<{width}}  {r['material']:<{material_width}}  {r['figure']}: {r['description']}")


@cli.command()
@click.option("--json", "as_json", is_flag=True, help="Print the table as JSON.")
@click.option("--size", default=512, show_default=True, type=click.IntRange(min=1), help="Sphere size for GPU timings.")
@click.option("--repeats", default=3, show_default=True, type=click.IntRange(min=1), help="Interleaved repeats per method (medians).")
@click.option("--thin-film", "film", is_flag=True,
              help="Instead: ΔE2000 of the thin-film methods (Figure 7, the presets) and their cost relative to GGX + Schlick.")
@click.option("--layers", is_flag=True,
              help="Instead: rough layers' host-table timings (F_alpha, a layer's tables) and the slice view's ΔE2000 (numpy, no GPU).")
@click.option("--app", "app", is_flag=True,
              help="Instead: the explorer's frame times while a slider is dragged, per method (a scripted session; Xvfb when there is no display).")
@click.option("--frames", "app_frames", type=click.IntRange(min=4), default=None, metavar="N",
              help="With --app: frames per drag (default 60, the docs' tables; fewer for a quick check).")
@click.option("--position-free", "position_free", is_flag=True,
              help="Instead: the position-free reference's time for a 9-angle albedo to a standard error of 2e-3 (numpy, no GPU).")
@click.option("--design", "design_count", type=click.IntRange(min=1), metavar="COUNT",
              help="Instead: COUNT random mirrors designed back from their colours at 5 angles (time, ΔE2000; 50 for the docs).")
@click.option("--seed", "design_seed", type=click.IntRange(min=0), default=None, metavar="SEED",
              help="With --design: the seed of the mirrors drawn and of their searches (default 0, the docs' set).")
@click.option("--tries", "design_tries", type=click.IntRange(min=1, max=MAX_TRIES), default=None, metavar="K",
              help=f"With --design: each design searches up to K times (design --tries; default {DEFAULT_TRIES}; 1: one search).")
@click.option("--tables", "tables", is_flag=True,
              help="Instead: host table rebuilds (converged table at N = 20, 100, 1000; a layer's tables) and the tabulated method's cost over Schlick's.")
@click.option("--scaling", "scaling", is_flag=True,
              help="Instead: table cost against N and table size, frame time against sphere size (with --plot PNG).")
@click.option("--plot", type=click.Path(dir_okay=False, writable=True), default=None, help="With --scaling: write the plot here.")
@click.option("--markdown", is_flag=True, help="Print Table 1, --thin-film or --layers as Markdown tables (docs/validation.md).")
@click.option("--mitsuba", "mitsuba", is_flag=True,
              help="Instead: Mitsuba's env-view frame times per variant beside GL's, and their median ΔE2000 (--size default 64 here; --spp).")
@click.option("--spp", type=click.IntRange(min=1), default=64, show_default=True, help="--mitsuba: samples per pixel.")
@click.option("--paint", "paint", is_flag=True,
              help="Instead: painting with structural colour on a local Dask cluster (--workers): a 64x64 round trip and a 256x256 "
                   "image of 8 regions, their ΔE2000 and times.")
@click.option("--workers", "paint_workers", type=click.IntRange(min=1), default=2, show_default=True, help="--paint: local Dask workers (the runs are timed on 1 worker and on this many).")
@_errors
def bench(as_json, size, repeats, film, layers, app, app_frames, position_free, design_count, design_seed, design_tries, tables, scaling,
          plot, markdown, mitsuba, spp, paint, paint_workers):
    """The paper's Table 1 on this machine: frame times, speed-ups and ΔE2000 of every method.

    With --thin-film: the thin-film methods of shaders/thin_film.brd (Belcour & Barla 2017).
    With --layers: the rough layers' host-table timings and the slice view's accuracy (64x64; --repeats, default 5 here).
    """
    from explorer.bench import run_bench, run_layers_bench, run_thin_film_bench

    if markdown and (as_json or app or position_free or design_count is not None or tables or scaling or mitsuba):
        raise click.UsageError("--markdown goes with Table 1, --thin-film or --layers, without --json")
    if design_seed is not None and design_count is None:
        raise click.UsageError("--seed goes with --design")
    if design_tries is not None and design_count is None:
        raise click.UsageError("--tries goes with --design")
    if app_frames is not None and not app:
        raise click.UsageError("--frames goes with --app")
    if paint:
        from explorer.bench.paint import run_paint_bench

        run_paint_bench(workers=paint_workers, as_json=as_json)
        return
    if position_free:
        from explorer.bench import run_position_free_bench

        run_position_free_bench(as_json=as_json)
        return
    if design_count is not None:
        from explorer.cli.design import run_design_bench

        run_design_bench(design_count, seed=design_seed or 0, as_json=as_json, tries=design_tries or DEFAULT_TRIES)
        return
    if scaling:
        from explorer.bench import run_scaling_bench

        run_scaling_bench(as_json=as_json, repeats=repeats, plot=Path(plot) if plot else None)
        return
    if tables:
        from explorer.bench import run_tables_bench

        source = click.get_current_context().get_parameter_source("repeats")
        run_tables_bench(as_json=as_json, size=size, repeats=repeats if source == click.core.ParameterSource.COMMANDLINE else 5)
        return
    if mitsuba:
        from explorer.mitsuba.bench import run_mitsuba_bench

        source = click.get_current_context().get_parameter_source("size")
        run_mitsuba_bench(as_json=as_json, size=size if source == click.core.ParameterSource.COMMANDLINE else 64, spp=spp,
                          echo=click.echo)
        return
    if app:
        from explorer.bench import run_app_bench

        run_app_bench(as_json=as_json, size=size, **({} if app_frames is None else {"frames": app_frames}))
        return
    if layers:
        if film:
            raise click.UsageError("--layers and --thin-film are exclusive")
        source = click.get_current_context().get_parameter_source("repeats")
        run_layers_bench(as_json=as_json, repeats=repeats if source == click.core.ParameterSource.COMMANDLINE else 5, markdown=markdown)
        return
    if film:
        run_thin_film_bench(as_json=as_json, size=size, repeats=repeats, markdown=markdown)
        return
    run_bench(as_json=as_json, size=size, repeats=repeats, markdown=markdown)


@cli.command()
@click.option("--json", "as_json", is_flag=True, help="Print the rows as JSON.")
@click.option("--plot", type=click.Path(dir_okay=False), help="Also write a PNG plot of median ΔE2000 against s.")
@click.option("--strips", type=click.Path(dir_okay=False), help="Also write Figure 4's colour strips (GPU) to a PNG.")
@click.option("--presets", "presets_", is_flag=True,
              help="Instead: median and max ΔE2000 per shipped Bragg preset (mirrors, layers, stacks' layers) and method.")
@click.option("--markdown", is_flag=True, help="Print the tables as Markdown (the Figure 4 grid, or with --presets docs/accuracy.md's).")
@_errors
def accuracy(as_json, plot, strips, presets_, markdown):
    """ΔE2000 of the approximations on the grid of Figure 4 (s = 2..8, both variants and numberings).

    With --presets: on every shipped preset's Bragg mirror, per method, over the gradient's angles.
    """
    if markdown and as_json:
        raise click.UsageError("--markdown and --json are exclusive")
    if presets_:
        if plot or strips:
            raise click.UsageError("--presets takes --json or --markdown, not --plot or --strips")
        from explorer.cli.accuracy import run_preset_accuracy

        run_preset_accuracy(as_json=as_json, markdown=markdown)
        return
    from explorer.bench import FIGURE_SUFFIXES, STRIP_SUFFIXES, figure4_strips, run_accuracy
    from explorer.files import check_output as check_file

    for path, suffixes in ((plot, FIGURE_SUFFIXES), (strips, STRIP_SUFFIXES)):
        if path:
            check_file(path, suffixes)  # before the seconds of work
    if strips:
        figure4_strips(Path(strips))
    run_accuracy(as_json=as_json, plot=Path(plot) if plot else None, markdown=markdown)


@cli.command("default", hidden=True)
@_errors
def default_job():
    """Render the default mirror to out/*.png: the main job where no display can show the app."""
    material = _load(DEFAULT_MATERIAL)
    values = material.resolve({"method": "3"})
    out = Path("out")
    out.mkdir(exist_ok=True)
    from explorer.gpu import Renderer

    renderer = Renderer()
    for view, size in (("sphere", (512, 512)), ("gradient", (512, 48))):
        image = renderer.render(material, values, view, *size)
        write_image(image, out / f"bragg_mirror_{view}.png")
        click.echo(f"wrote out/bragg_mirror_{view}.png ({size[0]}x{size[1]}, exact spectral colours, tabulated)")


from explorer.cli.inverse import figure_command, inverse_command  # noqa: E402  (the layered lobes' commands)
from explorer.cli.albedo import albedo_command  # noqa: E402

cli.add_command(inverse_command)
cli.add_command(figure_command)
cli.add_command(albedo_command)

from explorer.cli.design import design_command  # noqa: E402  (inverse design of mirrors and films)

cli.add_command(design_command)

from explorer.cli.export import export_command  # noqa: E402  (materials out: Mitsuba, BRDF Explorer, tables)
from explorer.cli.check import check_command  # noqa: E402  (GLSL against the numpy twin, for material authors)

cli.add_command(export_command)
cli.add_command(check_command)

from explorer.cli.spectrum import spectrum_command  # noqa: E402  (exact spectra of natural mirrors)

cli.add_command(spectrum_command)


def main(argv: list[str] | None = None) -> None:
    """
    Entry point: click's usage errors too end as one line (not click's usage block), and so does an
    unexpected error, said to be a bug (its traceback with ``--debug`` or ``BRAGG_EXPLORER_DEBUG=1``).
    """
    import signal
    import threading

    argv = list(sys.argv[1:] if argv is None else argv)
    debug = _debug(argv)
    if "--debug" in argv[1:]:  # after the command too (the group's own option comes first)
        argv = argv[:1] + [a for a in argv[1:] if a != "--debug"]
    main_thread = threading.current_thread() is threading.main_thread()
    previous = signal.signal(signal.SIGTERM, _terminate) if main_thread else None
    try:
        cli.main(args=argv, prog_name=PROG, standalone_mode=False)
    except click.exceptions.Exit as exit_:
        sys.exit(exit_.exit_code)
    except click.exceptions.Abort:
        _fail("aborted")
    except click.ClickException as error:
        click.echo(f"{PROG}: error: {' '.join(error.format_message().split())[:500]}", err=True)
        sys.exit(error.exit_code)
    except (LocatedError, OutputError) as error:  # bad input that a command did not turn into a line itself
        _fail(str(error))
    except MemoryError:
        _fail("out of memory (a smaller --size, --samples or input image needs less)")
    except RecursionError:
        _fail("input nested too deeply")
    except Exception as error:  # the last resort: each known bad input has its own message above
        if debug:
            import traceback

            traceback.print_exc()
        what = " ".join(str(error).split())[:200]
        _fail(f"internal error (a bug): {type(error).__name__}{': ' + what if what else ''}; "
              f"run with --debug (bragg-explorer --debug ...) or {DEBUG_ENV}=1 for the traceback")
    finally:
        if main_thread and previous is not None:
            signal.signal(signal.SIGTERM, previous)


if __name__ == "__main__":
    main()
