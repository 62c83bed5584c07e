"""
``bragg-explorer export MATERIAL --to {mitsuba,brdf,table,materialx} OUT``: a material out of the explorer
(docs/export.md, docs/mitsuba.md), and ``render --engine mitsuba``'s checks.
"""

from __future__ import annotations

from pathlib import Path

import click

from explorer.cli.materials import PROG, load, resolve_values, warn  # noqa: F401
TARGETS = ("mitsuba", "brdf", "table", "materialx", "gltf", "blender")


def check_mitsuba_render(view: str, engine: str, variant: str | None) -> None:
    """``--engine mitsuba`` renders the env view only; ``--variant`` belongs to it."""
    if engine == "mitsuba" and view != "env":
        raise click.BadParameter("--engine mitsuba renders the env view (--view env)", param_hint="--engine")
    if variant is not None and engine != "mitsuba":
        raise click.BadParameter("--variant is for --engine mitsuba", param_hint="--variant")


@click.command("export")
@click.argument("material", type=click.Path(dir_okay=False))
@click.option("--to", "target", type=click.Choice(TARGETS), required=True,
              help="mitsuba: a scene directory; brdf: one self-contained BRDF Explorer file; "
                   "table: an EXR of reflectance(cos theta[, roughness]); materialx: a .mtlx (a thin film); "
                   "gltf: a .glb sphere with KHR_materials_iridescence (a thin film, or the nearest one).")
@click.option("--preset", metavar="NAME", help="Start from a preset of the material; --set overrides it.")
@click.option("--params", "params_file", metavar="FILE", help="A parameter set (JSON or .bparam); over --preset, under --set.")
@click.option("--set", "assignments", multiple=True, metavar="NAME=VALUE", help="Set a material parameter (repeatable).")
@click.option("--env", "env_file", metavar="FILE", help="mitsuba: the environment (.hdr or .exr; default the env view's).")
@click.option("--mesh", metavar="FILE", help="mitsuba: an .obj or .ply in place of the unit sphere; gltf: an .obj or teapot, cube, torus.")
@click.option("--texture-table", is_flag=True, help="gltf: embed the exact reflectance table too (extras; docs/export.md).")
@click.option("--blender-film", type=click.Choice(("table", "principled")), default="table", show_default=True,
              help="blender: a thin film or a stack of interfaces as its converged table, or Principled's own inputs (docs/blender.md).")
@click.option("--spp", type=click.IntRange(min=1), default=256, show_default=True, help="mitsuba: samples per pixel.")
@click.argument("out", type=click.Path())
def export_command(material, target, preset, params_file, assignments, env_file, mesh, texture_table, blender_film, spp, out):
    """Write MATERIAL (a file or a built-in's name) for use elsewhere, to OUT (a directory for --to mitsuba)."""
    from explorer.errors import LocatedError
    from explorer.views.images import OutputError

    from explorer.cli.albedo import progress_while

    try:
        if texture_table and target != "gltf":
            raise click.BadParameter("--texture-table is for --to gltf", param_hint="--texture-table")
        loaded = load(material)
        with progress_while(f"export --to {target}"):
            if target == "blender":
                _export_blender(material, preset, params_file, assignments, env_file, out, loaded, blender_film)
            elif target == "gltf":
                _export_gltf(material, preset, params_file, assignments, env_file, mesh, texture_table, out, loaded)
            else:
                _export(material, target, preset, params_file, assignments, env_file, mesh, spp, out, loaded)
    except (LocatedError, OutputError) as error:  # bad input: one line (as commands._errors)
        click.echo(f"{PROG}: error: {error}", err=True)
        raise SystemExit(1) from None


def _export_blender(material, preset, params_file, assignments, env_file, out, loaded, film="table"):
    """``--to blender``: the preview scene (.blend) and the script that rebuilds the material (.py)."""
    from explorer.blender import export_blender
    from explorer.views.env import DEFAULT_ENVIRONMENT, EnvironmentMap

    for warning in loaded.warnings:
        warn(warning)
    values = resolve_values(loaded, preset, params_file, assignments)
    environment = EnvironmentMap.load(env_file if env_file is not None else DEFAULT_ENVIRONMENT)
    blend, script = export_blender(loaded, values, Path(out), environment, film=film)
    click.echo(f"wrote {blend} (Cycles preview: the env view's scene) and {script} (rebuilds the material on yours)")


def _export_gltf(material, preset, params_file, assignments, env_file, mesh, texture_table, out, loaded):
    """``--to gltf``: the .glb, and the film's ΔE2000 per angle on stdout."""
    from explorer.materials.export_gltf import export_gltf
    from explorer.views.mesh import mesh_named

    for warning in loaded.warnings:
        warn(warning)
    if env_file is not None:
        raise click.BadParameter("--env is for --to mitsuba", param_hint="--env")
    values = resolve_values(loaded, preset, params_file, assignments)
    shape = None
    if mesh is not None:
        m = mesh_named(mesh)
        shape = (m.positions, m.normals, m.triangles)
    path, film = export_gltf(loaded, values, Path(out), shape, texture_table)
    from explorer.materials.export_gltf import describe

    click.echo(describe(film))
    click.echo(f"wrote {path} (glTF 2.0, KHR_materials_iridescence; the ΔE per angle in the material's extras)")


def _export(material, target, preset, params_file, assignments, env_file, mesh, spp, out, loaded):
    """The export itself (bad input raises LocatedError / OutputError / click.BadParameter)."""
    for warning in loaded.warnings:
        warn(warning)
    values = resolve_values(loaded, preset, params_file, assignments)
    if target == "mitsuba":
        from explorer.mitsuba.export import export_scene
        from explorer.views.env import DEFAULT_ENVIRONMENT, EnvironmentMap

        environment = EnvironmentMap.load(env_file if env_file is not None else DEFAULT_ENVIRONMENT)
        path = export_scene(loaded, values, out, environment, mesh, spp)
        click.echo(f"wrote {path} (load it with explorer.mitsuba.load_file)")
        return
    if env_file is not None or mesh is not None:
        raise click.BadParameter("--env and --mesh are for --to mitsuba", param_hint="--to")
    if target == "brdf":
        from explorer.materials.export_brdf import export_brdf

        path, bparam = export_brdf(loaded, values, Path(out))
        click.echo(f"wrote {path} and {bparam} (Disney BRDF Explorer: File > Open BRDF, either file)")
    elif target == "table":
        from explorer.materials.export_table import TableExportError, material_table
        from explorer.views.images import write_image

        path = Path(out)
        if path.suffix.lower() != ".exr":
            raise TableExportError(path, None, "the table is an OpenEXR file: name it .exr")
        from explorer.cli.albedo import progress_printer

        table = material_table(loaded, values, progress_printer("table", "rows"))
        write_image(table, path)  # atomically
        click.echo(f"wrote {path} ({table.shape[1]}x{table.shape[0]} RGB, docs/export.md)")
    else:
        from explorer.materials.export_materialx import export_materialx

        path = export_materialx(loaded, values, Path(out))
        click.echo(f"wrote {path} (MaterialX standard_surface with thin_film_thickness and thin_film_IOR)")
