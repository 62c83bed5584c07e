"""
``bragg-explorer check MATERIAL [--views …] [--json]``: a material's GLSL against its numpy twin, view by
view, under the test suite's named tolerances (:mod:`explorer.views.twin_check`). For anyone writing a
material (docs/plugins.md): the exit status is non-zero when one view is over its tolerance. The sizes are small
(:data:`explorer.views.twin_check.CHECK_SIZES`): measured on a loaded 2-core llvmpipe machine, 9 s (GGX) to 70 s (a
spectral stack, whose env integral costs most) a material.
"""

from __future__ import annotations

import json

import click

from explorer.cli.materials import PROG, load, resolve_values


def _fail(message: str) -> None:
    click.echo(f"{PROG}: error: {message}", err=True)
    raise SystemExit(1)


@click.command("check")
@click.argument("material", type=click.Path(dir_okay=False))
@click.option("--views", metavar="VIEW,VIEW,...", help="The views to compare (default: every view the material supports).")
@click.option("--preset", metavar="NAME", help="Start from a preset of the material; --set overrides it.")
@click.option("--params", "params_file", metavar="FILE", help="A parameter set (JSON or .bparam); over --preset, under --set.")
@click.option("--set", "assignments", multiple=True, metavar="NAME=VALUE", help="Set a material parameter (repeatable).")
@click.option("--json", "as_json", is_flag=True, help='Print {"material": ..., "views": [{"view", "max_difference", "worst_ratio", "passed", ...}]}.')
def check_command(material, views, preset, params_file, assignments, as_json):
    """Render MATERIAL (a file, or a built-in's name) in GL and in numpy, view by view, and print the largest
    difference per view against its named tolerance; exit status 1 when any view is over it."""
    from explorer.errors import LocatedError
    from explorer.gpu import GLUnavailable, Renderer
    from explorer.materials.brd import MaterialError
    from explorer.materials.methods import opening_values
    from explorer.materials.twins import capabilities_of
    from explorer.resources import display_path
    from explorer.gpu.twin_check import check_material
    from explorer.views.twin_check import CHECK_SIZES, check_views

    try:
        loaded = load(material)
        if not capabilities_of(loaded).numpy:
            raise MaterialError(loaded.path, None, "this material has no numpy twin to check against (no known '# model:' "
                                "line, and no Python file of the same name beside it)")
        supported = check_views(loaded)
        chosen = supported if views is None else tuple(v.strip() for v in views.split(",") if v.strip())
        unknown = [v for v in chosen if v not in supported]
        if unknown or not chosen:
            others = [v for v in CHECK_SIZES if v not in supported]
            raise click.BadParameter(f"{', '.join(unknown) or 'none'}: check compares {', '.join(supported)} for this material"
                                     + (f" ({', '.join(others)}: it has no reflectance(cos_theta))" if others else ""),
                                     param_hint="--views")
        values = resolve_values(loaded, preset, params_file, assignments, opening_values(loaded))
        from explorer.cli.albedo import progress_while

        with progress_while(f"check {', '.join(chosen)}"):
            results = check_material(Renderer(), loaded, values, chosen)
    except (LocatedError, GLUnavailable, ValueError) as error:
        _fail(str(error))
    failed = [r for r in results if not r.passed]
    if as_json:
        click.echo(json.dumps({"material": display_path(loaded.path), "passed": not failed,
                               "views": [r.as_dict() for r in results]}, indent=2))
    else:
        click.echo(f"{display_path(loaded.path)}: GL against the numpy twin, largest difference per view")
        width = max(len(r.view) for r in results)
        for r in results:
            verdict = "ok" if r.passed else "OVER"
            if r.non_finite:
                click.echo(f"  {r.view:<{width}}  {r.non_finite} non-finite  {verdict}")
                continue
            click.echo(f"  {r.view:<{width}}  max |GL - numpy| {r.max_difference:.2e}, worst pixel {r.worst_ratio:.2f} of "
                       f"its allowed {r.allowed:.1e} ({r.tolerance.name})  {verdict}")
        click.echo(f"{len(results) - len(failed)} of {len(results)} views within tolerance"
                   + (f"; over: {', '.join(r.view for r in failed)}" if failed else ""))
    if failed:
        raise SystemExit(1)
