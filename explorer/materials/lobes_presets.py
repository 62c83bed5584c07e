"""
The presets of ``shaders/layered_lobes.brd`` (``shaders/presets/layered_lobes.toml``): the lobes of
Bati, Barla & Pacanowski's (2021) figures, turned into stacks by our inverse method.

The paper gives its figures' lobes (energy and variance at normal incidence) and lists the retrieved
physical parameters only in its supplemental material, which we do not have: every stack here is ours,
computed by :func:`explorer.physics.inverse.invert_lobes` from the figure's lobes with the choices recorded
below (the default point of each equivalence class unless stated). ``python -m explorer.materials.lobes_presets``
rewrites the TOML file and prints the figures' lobes that no stack of our model achieves.
"""

from __future__ import annotations

from pathlib import Path

from explorer.physics.inverse import InverseError, Lobe, invert_lobes
from explorer.materials.lobes_model import values_from_stack
from explorer.files import write_text_atomic
from explorer.resources import PRESET_DIR

PRESET_FILE = PRESET_DIR / "layered_lobes.toml"

#: name -> (figure, what it shows, lobes top first, choices per lobe).
FIGURES: dict[str, tuple] = {
    "figure5a_dielectric": ("Figure 5(a)", "1-layer dielectric lobe in air, R = 0.04 (smooth)", [Lobe(0.04, 0.0)], None),
    "figure5b_conductor_edge_tint": ("Figure 5(b)", "1-layer conductor in air, R = 0.6, eta at Eq. 10's bound (largest edge tint), smooth (ours)",
                                     [Lobe(0.6, 0.0, base="conductor")], [{"t": 0.0}]),
    "figure5b_conductor_kappa_eq_eta": ("Figure 5(b)", "1-layer conductor in air, R = 0.6, eta at Eq. 9's bound (kappa = eta), smooth (ours)",
                                        [Lobe(0.6, 0.0, base="conductor")], [{"t": 1.0}]),
    "figure5c_coated_conductor_edge_tint": ("Figure 5(c)", "the conductor of 5(b) under a clear coat (R = 0.04, ours) keeping its R = 0.6, Eq. 10's bound",
                                            [Lobe(0.04, 0.0), Lobe(0.6, 0.0, base="conductor")], [{}, {"t": 0.0}]),
    "figure5c_coated_conductor_kappa_eq_eta": ("Figure 5(c)", "the same at Eq. 9's bound",
                                               [Lobe(0.04, 0.0), Lobe(0.6, 0.0, base="conductor")], [{}, {"t": 1.0}]),
    "figure10a_two_layer": ("Figure 10(a)", "2-layer dielectric lobe R = 0.15, sigma = 0, default point of its class (ours)",
                            [Lobe(0.15, 0.0, layers=2)], None),
    "figure10a_slab": ("Figure 10(a)", "the same lobe as a slab: eta_2 = 1 (point E of Fig. 7a; eta_1 = 1.82 ours)",
                       [Lobe(0.15, 0.0, layers=2)], [{"eta": 1.0, "eta_top": 1.82}]),
    "figure10b_absorbing": ("Figure 10(b)", "2-layer lobe R = 0.15 with achromatic absorption tau_1 > 0 (eta_1 = 1.3, eta_2 = 3.5, ours)",
                            [Lobe(0.15, 0.0, layers=2)], [{"eta": 3.5, "eta_top": 1.3}]),
    "figure10c_rough": ("Figure 10(c)", "2-layer lobe R = 0.15, sigma = 0.02", [Lobe(0.15, 0.02, layers=2)], None),
    "figure14a_conductor": ("Figure 14(a)", "1-layer conductor R = [0.9, 0.7, 0.5], sigma = 0.03, in air",
                            [Lobe([0.9, 0.7, 0.5], 0.03, base="conductor")], None),
    "figure14a_coated": ("Figure 14(a)", "the same lobe kept under a clear coat (R = 0.04, sigma = 0: ours)",
                         [Lobe(0.04, 0.0), Lobe([0.9, 0.7, 0.5], 0.03, base="conductor")], None),
    "figure14b_two_layer": ("Figure 14(b)", "2-layer dielectric lobe R = [0.1, 0.2, 0.1], sigma = 0.03", [Lobe([0.1, 0.2, 0.1], 0.03, layers=2)], None),
    "figure14b_coated": ("Figure 14(b)", "the same lobe kept under a clear coat (R = 0.04, sigma = 0: ours)",
                         [Lobe(0.04, 0.0), Lobe([0.1, 0.2, 0.1], 0.03, layers=2)], None),
    "figure15a_achromatic": ("Figure 15(a)", "2-layer lobe R = 0.15, smooth, low tau_1 (eta_1 = 1.2, ours)", [Lobe(0.15, 0.0, layers=2)], [{"eta_top": 1.2}]),
    "figure15b_purple_low_tau": ("Figure 15(b)", "2-layer lobe R = [0.09, 0.09, 0.15], smooth, low tau_1 (default point, ours)",
                                 [Lobe([0.09, 0.09, 0.15], 0.0, layers=2)], None),
    "figure15b_purple_high_tau": ("Figure 15(b)", "the same lobe with higher tau_1 (eta_1 = 1.2, eta_2 = 3.6: ours)",
                                  [Lobe([0.09, 0.09, 0.15], 0.0, layers=2)], [{"eta_top": 1.2, "eta": 3.6}]),
    "figure15c_purple_rough": ("Figure 15(c)", "2-layer lobe R = [0.09, 0.09, 0.15], sigma = 0.03", [Lobe([0.09, 0.09, 0.15], 0.03, layers=2)], None),
    "figure16_reference": ("Figure 16", "2-layer conductor lobe R = 0.45, sigma = 0.03 (reference, default point: ours)",
                           [Lobe(0.45, 0.03, layers=2, base="conductor")], None),
    "figure16a_lower_eta1": ("Figure 16(a)", "the same lobe with a lower eta_1 = 1.2 (ours)", [Lobe(0.45, 0.03, layers=2, base="conductor")], [{"eta_top": 1.2}]),
    "figure16b_green_tau": ("Figure 16(b)", "the same lobe with tau_1 raised on green only (0, 0.3, 0: ours): pink edge tint",
                            [Lobe(0.45, 0.03, layers=2, base="conductor")], [{"tau": [0.0, 0.3, 0.0]}]),
    "figure16c_both": ("Figure 16(c)", "both variations (eta_1 = 1.2, tau_1 = 0, 0.3, 0: ours)",
                       [Lobe(0.45, 0.03, layers=2, base="conductor")], [{"eta_top": 1.2, "tau": [0.0, 0.3, 0.0]}]),
    "figure18_queen": ("Figure 18", "Queen: 2-layer dielectric lobe R = [0.03, 0.06, 0.09], sigma = 0.05", [Lobe([0.03, 0.06, 0.09], 0.05, layers=2)], None),
    "figure18a_rook": ("Figure 18(a)", "Rook: desaturated, R = [0.06, 0.06, 0.06], sigma = 0.05", [Lobe([0.06, 0.06, 0.06], 0.05, layers=2)], None),
    "figure18a_knight": ("Figure 18(a)", "Knight: saturated, R = [0.01, 0.06, 0.11], sigma = 0.05", [Lobe([0.01, 0.06, 0.11], 0.05, layers=2)], None),
    "figure18b_rook": ("Figure 18(b)", "Rook: sharper, R = [0.03, 0.06, 0.09], sigma = 0", [Lobe([0.03, 0.06, 0.09], 0.0, layers=2)], None),
    "figure18b_knight": ("Figure 18(b)", "Knight: blurrier, R = [0.03, 0.06, 0.09], sigma = 0.15", [Lobe([0.03, 0.06, 0.09], 0.15, layers=2)], None),
    "figure19a_subtle_haze": ("Figure 19(a)", "smooth coat R = 0.1 over a conductor R = [0.35, 0.25, 0.3], sigma_2 = 0.01",
                              [Lobe(0.1, 0.0), Lobe([0.35, 0.25, 0.3], 0.01, base="conductor")], None),
    "figure19b_haze": ("Figure 19(b)", "the same with sigma_2 = 0.04", [Lobe(0.1, 0.0), Lobe([0.35, 0.25, 0.3], 0.04, base="conductor")], None),
    "figure19c_strong_haze": ("Figure 19(c)", "the same with sigma_2 = 0.1", [Lobe(0.1, 0.0), Lobe([0.35, 0.25, 0.3], 0.1, base="conductor")], None),
    "figure20_coloured_highlight": ("Figure 20 (left)", "2-layer coat R1 = [0.09, 0.14, 0.09], sigma1 = 0.005 over a 1-layer dielectric base R2 = 0.09, sigma2 = 0.1",
                                    [Lobe([0.09, 0.14, 0.09], 0.005, layers=2), Lobe(0.09, 0.1)], None),
    "figure20_coloured_halo": ("Figure 20 (right)", "the lobe colours swapped: R1 = 0.09, R2 = [0.09, 0.14, 0.09]",
                               [Lobe(0.09, 0.005, layers=2), Lobe([0.09, 0.14, 0.09], 0.1)], None),
    "figure21_left": ("Figure 21 (left)", "1-layer dielectric R1 = 0.04, sigma1 = 0.07 over a conductor R2 = [0.6, 0.25, 0.25], sigma2 = 0.03",
                      [Lobe(0.04, 0.07), Lobe([0.6, 0.25, 0.25], 0.03, base="conductor")], None),
    "figure21_right": ("Figure 21 (right)", "the variances swapped: sigma1 = 0.03, sigma2 = 0.07",
                       [Lobe(0.04, 0.03), Lobe([0.6, 0.25, 0.25], 0.07, base="conductor")], None),
    "figure17_blue_on_red": ("Figure 17 (left)", "the blue lobe's top interface at eta = 1 (ours: the only eta_top whose transmitted variance leaves the red lobe's 0.014 reachable); 2-layer blue lobe R = [0.025, 0.045, 0.05], sigma = 0.028 over a 2-layer red one R = [0.052, 0.025, 0.025], sigma = 0.014",
                             [Lobe([0.025, 0.045, 0.05], 0.028, layers=2), Lobe([0.052, 0.025, 0.025], 0.014, layers=2)],
                             [{"eta_top": 1.0}, {}]),
    "figure17_red_on_blue": ("Figure 17 (right)", "the order swapped",
                             [Lobe([0.052, 0.025, 0.025], 0.014, layers=2), Lobe([0.025, 0.045, 0.05], 0.028, layers=2)], None),
}


def _value_text(value) -> str:
    if isinstance(value, list):
        return '"' + ",".join(f"{v:.6g}" for v in value) + '"'
    if isinstance(value, float):
        return f"{value:.6g}"
    return str(value)


def build():
    """``(presets, failures)``: name -> (figure, description, values), and name -> the inverse's message."""
    presets, failures = {}, {}
    for name, (figure, description, lobe_list, choices) in FIGURES.items():
        try:
            stack = invert_lobes(lobe_list, choices)
        except InverseError as error:
            failures[name] = f"{figure}: {error}"
            continue
        chosen = "" if not choices or not any(choices) else f"; choices {choices}"
        presets[name] = (figure, f"{description} (stack from our inverse method{chosen}; the paper's parameters are in its supplemental)",
                         values_from_stack(stack))
    return presets, failures


def write(path: Path = PRESET_FILE) -> dict:
    presets, failures = build()
    lines = [
        "# Presets of shaders/layered_lobes.brd: the lobes of Bati, Barla & Pacanowski (2021), An inverse method for the",
        "# exploration of layered material appearance (../shared/papers/bati2021-inverse-layered.md), Figures 5, 10, 14-21.",
        "#",
        "# Generated by `python -m explorer.materials.lobes_presets`: the paper gives each figure's lobes (energy R and variance",
        "# sigma at normal incidence); the physical parameters below are ours, retrieved by explorer.physics.inverse from those",
        "# lobes at the default point of each equivalence class or at the choices in the description.",
        "# Figure 1 shows materials of Figures 14-21; Figure 22's three lobes are given only in the supplemental.",
    ]
    for name, message in failures.items():
        lines.append(f"# Not achievable by our model: {name}: {message}")
    lines += ["", 'material = "layered_lobes.brd"']
    for name, (figure, description, values) in presets.items():
        lines += ["", f"[{name}]", f'figure = "{figure}"', f'description = "{description}"']
        lines += [f"{key} = {_value_text(value)}" for key, value in values.items()]
    write_text_atomic(path, "\n".join(lines) + "\n")
    return failures


def main() -> int:
    from explorer.resources import require_checkout

    require_checkout("python -m explorer.materials.lobes_presets")
    failures = write()
    print(f"wrote {PRESET_FILE}")
    for name, message in failures.items():
        print(f"not achievable: {name}: {message}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
