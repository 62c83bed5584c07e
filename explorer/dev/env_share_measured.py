"""
The env view's share of environment samples, measured (docs/meshes.md): the RMS error against a converged render
at equal samples, with the share fixed at one half (before), the material's sampling alone, and each pixel's
share following its lobes (:func:`explorer.views.env.environment_share`, after); printed as Markdown
(``python -m explorer.dev.env_share_measured``; about a minute on llvmpipe), and the sweep the share's
constants were fitted on (the best fixed share per GGX lobe and environment).

Measured, not asserted. The converged render is the GL estimate at :data:`CONVERGED_SPP` samples per pixel
(per-pixel shares, another seed): its own RMS error is 1/16 of the 64-sample renders', and adds under 0.2 %
to theirs.
"""

from __future__ import annotations

import numpy as np

from explorer.gpu import Renderer
from explorer.gpu.env import ENVIRONMENT_SAMPLING_WEIGHT, ProgressiveEnvRender
from explorer.materials.brd import load_material
from explorer.materials.methods import BraggMethod
from explorer.materials.models import BraggLayerModel, GGXSchlickModel
from explorer.materials.twins import shipped_file
from explorer.views.env import ENVIRONMENTS, environment_solid_angle
from explorer.views.geometry import brdf_view_geometry

SIZE, SPP, SEEDS, CONVERGED_SPP = 32, 64, (1, 2, 3, 4), 16384
#: (label, twin class of the shipped material, overrides): a sharp, a medium and a rough GGX lobe, and a Bragg layer over a base.
CASES = (
    ("ggx alpha 0.05 (sharp)", GGXSchlickModel, {"alpha": 0.05, "F0": 0.9}),
    ("ggx alpha 0.2 (medium)", GGXSchlickModel, {"alpha": 0.2, "F0": 0.9}),
    ("ggx alpha 0.6 (rough)", GGXSchlickModel, {"alpha": 0.6, "F0": 0.9}),
    (f"{BraggLayerModel.name} alpha 0.1, rho_d 0.5", BraggLayerModel, {"alpha": 0.1, "method": int(BraggMethod.TABULATED), "rho_d": 0.5}),
)
#: The shares compared: fixed at one half (before), the material's sampling alone, per pixel (after).
SHARES = {"0.5 fixed": ENVIRONMENT_SAMPLING_WEIGHT, "0 (BRDF only)": 0.0, "per pixel": None}


def _render(renderer, material, values, environment, spp: int, share, seed: int) -> np.ndarray:
    render = ProgressiveEnvRender(renderer, material, values, environment, SIZE, SIZE, environment_sampling=share, seed=seed)
    try:
        render.step(spp)
        return render.image().astype(np.float64)
    finally:
        render.release()


def rows(renderer: Renderer) -> list[str]:
    inside = brdf_view_geometry("lit", SIZE, SIZE)[5]
    lines = ["| environment | material | " + " | ".join(f"RMS error, share {name}" for name in SHARES) + " | after / before |",
             "|---|---|" + "---|" * (len(SHARES) + 1)]
    for env_name in ("sky", "studio"):
        environment = ENVIRONMENTS[env_name]()
        for label, path, overrides in CASES:
            material = load_material(shipped_file(path))
            values = material.resolve(overrides)
            converged = _render(renderer, material, values, environment, CONVERGED_SPP, None, seed=99)
            errors = {}
            for name, share in SHARES.items():
                squares = [np.mean((_render(renderer, material, values, environment, SPP, share, seed) - converged)[inside] ** 2)
                           for seed in SEEDS]
                errors[name] = float(np.sqrt(np.mean(squares)))
            cells = " | ".join(f"{errors[name]:.4f}" for name in SHARES)
            lines.append(f"| {env_name} | {label} | {cells} | {errors['per pixel'] / errors['0.5 fixed']:.2f} |")
    return lines


#: The fit's sweep: GGX lobes (F0 0.9) and the fixed shares tried, the RMS standard error at 512 spp, 24².
SWEEP_ALPHAS = (0.02, 0.05, 0.1, 0.2, 0.3, 0.45, 0.6, 1.0)
SWEEP_SHARES = (0.0, 0.02, 0.05, 0.1, 0.15, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9)


def sweep_rows(renderer: Renderer) -> list[str]:
    """Per GGX lobe and environment: the best fixed share and the per-pixel share's error relative to it."""
    size, spp = 24, 512
    inside = brdf_view_geometry("lit", size, size)[5]
    material = load_material(shipped_file(GGXSchlickModel))

    def rms(values, environment, share) -> float:
        render = ProgressiveEnvRender(renderer, material, values, environment, size, size, environment_sampling=share, seed=3)
        try:
            render.step(spp)
            return float(np.sqrt(np.mean(render.standard_error()[inside].astype(np.float64) ** 2)))
        finally:
            render.release()

    lines = ["| environment | alpha | best fixed share | per pixel / best fixed | per pixel / fixed 0.5 |", "|---|---|---|---|---|"]
    for env_name in ("sky", "studio"):
        environment = ENVIRONMENTS[env_name]()
        for alpha in SWEEP_ALPHAS:
            values = material.resolve({"alpha": alpha, "F0": 0.9})
            fixed = [rms(values, environment, share) for share in SWEEP_SHARES]
            best = int(np.argmin(fixed))
            adaptive = rms(values, environment, None)
            lines.append(f"| {env_name} | {alpha} | {SWEEP_SHARES[best]} | {adaptive / fixed[best]:.2f} | "
                         f"{adaptive / fixed[SWEEP_SHARES.index(ENVIRONMENT_SAMPLING_WEIGHT)]:.2f} |")
    return lines


def main() -> None:
    renderer = Renderer()
    solid_angles = ", ".join(f"{name} {environment_solid_angle(ENVIRONMENTS[name]()):.2f} sr" for name in ("sky", "studio"))
    print(f"RMS error against a {CONVERGED_SPP}-spp render, {SPP} spp at {SIZE}², {len(SEEDS)} seeds; "
          f"effective solid angles: {solid_angles}\n")
    print("\n".join(rows(renderer)))
    print("\nThe fit's sweep: RMS standard error at 512 spp, 24², GGX lobes (F0 0.9), fixed shares "
          f"{', '.join(map(str, SWEEP_SHARES))}\n")
    print("\n".join(sweep_rows(renderer)))


if __name__ == "__main__":
    main()
