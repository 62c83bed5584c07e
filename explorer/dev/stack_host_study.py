"""
A layered Bragg structure in a dispersive host (docs/natural.md): what the per-wavelength refraction changes, and
what it costs. ``python3 -m explorer.dev.stack_host_study`` prints Markdown.

- Colour: the stack with its host's index per wavelength (Snell angle, coating Fresnel terms, ``1/nh^2``), against
  the same stack and the same tables with every wavelength refracted at the host's 550-nm index, as ΔE2000 of the
  smooth limit's colour (the gradient view, 0-85 degrees) and of the albedo (the albedo command's numpy engine).
- Cost: CPU seconds of the numpy albedo (``time.process_time``), and the GL albedo's wall-clock ratio in one run,
  each against the same structure in a host of one index.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from explorer.materials.brd import load_material
from explorer.materials.models import BraggStackModel, model_for
from explorer.materials.twins import shipped_file
from explorer.physics import colorimetry, layered

#: Two layers under each host, a coloured base (the hosts the library has that a stack takes).
CASES = {
    "chitin": {"nh": "chitin", "n1_1": "chitin"},
    "keratin": {"nh": "keratin", "n1_1": "keratin"},
    "water": {"nh": "water", "n1_1": "water"},
    "guanine": {"nh": "guanine", "n1_1": "guanine"},
}
BASE = {"layers": "2", "n2_1": "1.7", "Lambda_1": "380", "N_1": "8", "alpha_1": "0.2", "n1_2": "1.3",
        "alpha_2": "0.3", "rho_d": "0.5,0.3,0.2", "multiple_scattering": "0"}
ANGLES = np.radians(np.arange(0.0, 86.0, 5.0))


def _at_550(material, values, model):
    """The same stack and tables, every wavelength refracted at the host's 550-nm index (one direction for all)."""
    stack = model.stack
    fixed = model_for(material, values)
    fixed.stack = layered.LayeredBragg(layers=stack.layers, n1=stack.n1, rho_d=stack.rho_d, coating=stack.coating, tau_h=stack.tau_h)
    fixed._tables = model.tables
    return fixed


def colour_rows() -> list[str]:
    from explorer.views.albedo import albedo_numpy

    material = load_material(shipped_file(BraggStackModel))
    rows = ["| host | n at 400 / 550 / 700 nm | gradient ΔE2000, max (angle) | albedo ΔE2000 at 0 / 40 / 70° | numpy albedo CPU s (one index) |",
            "|---|---|---|---|---|"]
    for name, host in CASES.items():
        values = material.resolve({**BASE, **host})
        model = model_for(material, values)
        fixed = _at_550(material, values, model)
        n = model.stack.host_index([400.0, 550.0, 700.0])
        exact, one = model.reflectance(np.cos(ANGLES)), fixed.reflectance(np.cos(ANGLES))
        gradient = colorimetry.delta_E_2000(exact, one)
        worst = int(np.argmax(gradient))
        start = time.process_time()
        albedo = albedo_numpy(model, [0.0, 40.0, 70.0])
        cost = time.process_time() - start
        plain = model_for(material, material.resolve({**BASE, "nh": f"{n[1]:.6f}", "n1_1": f"{n[1]:.6f}"}))
        start = time.process_time()
        albedo_numpy(plain, [0.0, 40.0, 70.0])
        cost_plain = time.process_time() - start
        one_albedo = albedo_numpy(fixed, [0.0, 40.0, 70.0])
        albedo_error = colorimetry.delta_E_2000(albedo, one_albedo)
        rows.append(f"| {name} | {n[0]:.4f} / {n[1]:.4f} / {n[2]:.4f} | {gradient[worst]:.2f} ({np.degrees(ANGLES[worst]):.0f}°) | "
                    + " / ".join(f"{e:.2f}" for e in albedo_error) + f" | {cost:.1f} ({cost_plain:.1f}) |")
    return rows


def gl_rows(repeats: int = 3) -> list[str]:
    from explorer.gpu.renderer import Renderer
    from explorer.views.albedo import albedo_gl

    material = load_material(shipped_file(BraggStackModel))
    renderer = Renderer()
    values = {name: material.resolve({**BASE, **host}) for name, host in (("chitin", CASES["chitin"]), ("one index", {"nh": "1.5561", "n1_1": "1.5561"}))}
    models = {name: model_for(material, v) for name, v in values.items()}
    times = {name: [] for name in values}
    for round_ in range(repeats + 1):
        for name, v in values.items():
            start = time.perf_counter()
            albedo_gl(material, v, [20.0], renderer, size=256, model=models[name])
            if round_:
                times[name].append(time.perf_counter() - start)
    chitin, one = (float(np.median(times[name])) for name in ("chitin", "one index"))
    return [f"GL albedo (scatter view, 256², llvmpipe), median of {repeats} interleaved: chitin host {chitin:.2f} s, "
            f"one index {one:.2f} s, ratio {chitin / one:.2f}"]


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument("--no-gl", action="store_true", help="Skip the GL timing.")
    args = parser.parse_args(argv)
    for line in colour_rows():
        print(line)
    if not args.no_gl:
        print()
        for line in gl_rows():
            print(line)


if __name__ == "__main__":
    main()
