"""
The RGB methods under a host and at low N (issue 16, item 5): the improved method on every shipped Bragg
preset, the accuracy badge (no window), ``accuracy --presets`` and ``render``'s note.

References are independent of the approximations: the converged spectral reference
(:func:`explorer.physics.bragg.reference_rgb`, Yeh's exact reflectance integrated until the colour
converges) and colour-science's ΔE2000.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from conftest import BRAGG_MATERIAL, run_cli

from explorer.cli.accuracy import exceptions, format_markdown, preset_accuracy, preset_mirrors
from explorer.materials.accuracy import ACCURACY_LIMIT, accuracy_badge, gradient_cos_theta, mirror_accuracy
from explorer.materials.brd import load_material
from explorer.physics import bragg, colorimetry

#: Gradient columns of the per-preset sweep in the tests (the badge's; the command uses 256).
TEST_WIDTH = 90


@pytest.fixture(scope="module")
def shipped_mirrors():
    return preset_mirrors()


def test_preset_mirrors_cover_hosts_low_N_and_stack_layers(shipped_mirrors):
    by_source = {source: entry.mirror for entry in shipped_mirrors for source in entry.sources}
    beetle = by_source["table3_green_blue"]
    assert (beetle.n1, beetle.n2, beetle.N, beetle.nh) == (1.59, 1.67, 8, 1.0)  # Appendix D: host air
    # A stack's layer is its mirror in the stack's host: the same mirror as the smooth preset's.
    assert by_source["table3_green_blue/layer 1"] == beetle
    assert min(entry.mirror.N for entry in shipped_mirrors) <= 3  # Figure 12's top layer
    # Identical mirrors are measured once.
    assert len({entry.mirror for entry in shipped_mirrors}) == len(shipped_mirrors)


@pytest.mark.slow
def test_improved_method_median_within_limit_on_every_shipped_preset(shipped_mirrors):
    """Method 4 (ours): median ΔE2000 <= 2 against the converged reference on every shipped Bragg mirror."""
    cos_theta = gradient_cos_theta(TEST_WIDTH)
    too_far = {}
    for entry in shipped_mirrors:
        reference = bragg.reference_rgb(cos_theta, entry.mirror)
        dE = colorimetry.delta_E_2000(reference, bragg.approximate_rgb(cos_theta, entry.mirror, 3, variant="improved"))
        if np.median(dE) > ACCURACY_LIMIT:
            too_far[entry.name] = round(float(np.median(dE)), 2)
    assert not too_far, f"improved method, median ΔE2000 above {ACCURACY_LIMIT}: {too_far}"


@pytest.mark.parametrize("N", [2, 3, 5, 8, 15])
@pytest.mark.parametrize("nh", [None, 1.0, 1.33])
def test_improved_method_at_low_N_under_a_host(N, nh):
    """Low N (>= 2) and hosts beyond the presets: weak and moderate contrast, median ΔE2000 <= 2."""
    cos_theta = gradient_cos_theta(32)
    for n1, n2, Lambda, delta in ((1.55, 1.65, 180.0, 0.5), (1.3, 1.8, 300.0, 0.4)):
        mirror = bragg.BraggMirror(n1, n2, Lambda, delta, N, nh)
        dE = colorimetry.delta_E_2000(bragg.reference_rgb(cos_theta, mirror),
                                      bragg.approximate_rgb(cos_theta, mirror, 3, variant="improved"))
        assert np.median(dE) <= ACCURACY_LIMIT, (mirror, float(np.median(dE)), float(dE.max()))


def test_gap_weight_tends_to_the_papers_unit_weight_for_large_N():
    """The improved gaps' weight is the exact reflectance mid-gap: the paper's w = 1 for large N (Eq. 9), far below for N = 8."""
    for N, low, high in ((200, 0.999, 1.0), (8, 0.0, 0.5)):
        mirror = bragg.BraggMirror(1.59, 1.67, 160.0, 0.51, N)
        g = bragg.cell_geometry(np.array([1.0]), mirror, "s")
        n_plus = bragg.optical_thickness(g)
        omega_m, omega_next = bragg.mode_frequency(1.0, n_plus), bragg.mode_frequency(2.0, n_plus)
        edge = bragg.band_edge(g, omega_m, bragg.airy_point(g, omega_m, omega_next, 1.0), True)
        w = float(bragg.gap_weight(omega_m, edge, g)[0])
        exact = float(bragg.bragg_reflectance(1.0, 4.0 * np.pi / float(omega_m[0] + edge[0]), mirror, "s"))
        assert low <= w <= high and w == pytest.approx(exact, abs=1e-9), (N, w, exact)


def test_badge_flags_the_basic_method_under_a_host_and_names_accurate_ones(bragg_material):
    from explorer.materials.presets import presets_for

    preset = presets_for(BRAGG_MATERIAL).get("table3_green_blue")
    badge = accuracy_badge(bragg_material, preset.resolve({"method": 1}))
    assert badge is not None and badge.method == 1 and not badge.accurate
    assert badge.current.dE_median > ACCURACY_LIMIT
    assert {3, 4} <= set(badge.accurate_methods())
    note = badge.note()
    assert note is not None and "method 1 basic is off" in note and "4 improved" in note and "\n" not in note
    improved = accuracy_badge(bragg_material, preset.resolve({"method": 4}))
    assert improved.accurate and improved.note() is None and "accurate" in improved.text()


def test_badge_reference_is_the_converged_spectra(bragg_material):
    """The badge's reference (the converged table, interpolated) agrees with the converged spectra."""
    mirror = bragg.BraggMirror(1.59, 1.67, 160.0, 0.51, 8, 1.0)
    cos_theta = gradient_cos_theta()
    from_table = mirror_accuracy(mirror, (1, 4), cos_theta=cos_theta)
    from_spectra = mirror_accuracy(mirror, (1, 4), cos_theta=cos_theta, reference=bragg.reference_rgb(cos_theta, mirror))
    for method in (1, 4):
        assert from_table[method].dE_median == pytest.approx(from_spectra[method].dE_median, abs=0.05)


def test_badge_only_for_materials_with_bragg_methods():
    stack = load_material(BRAGG_MATERIAL.parent / "bragg_stack.brd")
    film = load_material(BRAGG_MATERIAL.parent / "thin_film.brd")
    assert accuracy_badge(stack, stack.resolve({})) is None
    assert accuracy_badge(film, film.resolve({})) is None
    layer = load_material(BRAGG_MATERIAL.parent / "bragg_layer.brd")
    assert accuracy_badge(layer, layer.resolve({"method": 2})) is not None


def test_preset_accuracy_rows_and_exceptions(shipped_mirrors):
    chosen = [e for e in shipped_mirrors if e.sources[0] in ("table3_green_blue", "figure3")]
    rows = preset_accuracy(chosen, width=16)
    assert [r["preset"] for r in rows] == ["figure3", "table3_green_blue"]
    json.dumps(rows)  # the --json output
    for row in rows:
        assert set(row["methods"]) == {"basic", "subdivided", "improved", "tabulated"}
        assert row["methods"]["tabulated"]["dE_median"] < 0.1  # the check: the table is converged
    found = exceptions(rows)
    assert "table3_green_blue" in found["basic"] and not found["improved"]
    markdown = format_markdown(rows, 16)
    others = len(next(e for e in chosen if e.sources[0] == "table3_green_blue").sources) - 1  # the same mirror's other presets
    assert f"| table3_green_blue (+{others}) |" in markdown and others >= 1 and "**basic**" in markdown


def test_accuracy_presets_rejects_plot():
    run = run_cli("accuracy", "--presets", "--plot", "x.png")
    assert run.returncode != 0 and len(run.stderr.strip().splitlines()) == 1


def test_render_notes_an_inaccurate_method(tmp_path):
    out = tmp_path / "g.npy"
    args = ("render", "bragg_mirror", "--preset", "table3_green_blue", "--view", "gradient", "--size", "16x1",
            "--engine", "numpy", "--out", out)
    off = run_cli(*args, "--set", "method=1")
    assert off.returncode == 0 and out.exists(), off.stderr
    notes = [line for line in off.stderr.splitlines() if "note:" in line]
    assert len(notes) == 1 and "method 1 basic is off" in notes[0] and "4 improved" in notes[0], off.stderr
    accurate = run_cli(*args, "--set", "method=4")
    assert accurate.returncode == 0 and "note:" not in accurate.stderr, accurate.stderr
