"""Real specimens (bragg_mirror presets from published measurements) and the lossless host's one-line refusal."""

from __future__ import annotations

import json

import numpy as np
import pytest

from conftest import REPO_ROOT, one_line_error, run_cli
from explorer.views.spectrum_plot import natural_mirror
from explorer.materials.media import host_problem
from explorer.materials.presets import PRESET_DIR, PresetError, load_presets
from explorer.physics import dispersion
from explorer.physics.bragg import BraggMirror
from explorer.physics.natural import NaturalMirror, mirror_spectrum

PRESETS = load_presets(PRESET_DIR / "bragg_mirror.toml")
SPECIMENS = {name: p for name, p in PRESETS.presets.items() if p.citation}
#: Published reflectance peaks at normal incidence (nm) and how far the model may sit from them: Stavenga
#: et al. (2011) give ~530 nm (green) and ~700 nm (purple) for the jewel beetle.
PUBLISHED_PEAKS = {"chrysochroa_fulgidissima_green": (530.0, 20.0), "chrysochroa_fulgidissima_purple": (700.0, 40.0)}


def test_five_cited_specimens_with_media_and_layer_counts():
    assert len(SPECIMENS) >= 5
    for name, preset in SPECIMENS.items():
        assert len(preset.citation) > 30 and any(str(year) in preset.citation for year in range(1990, 2030)), name
        assert {"n1", "n2", "Lambda", "delta", "N", "nh"} <= set(preset.values), name
    # Bird barbules use the shipped keratin and melanin dispersions (resolved as media, not numbers).
    mirror = natural_mirror(dict(SPECIMENS["parotia_lawesii_occipital"].resolve()), {})
    assert mirror.n1 is dispersion.LIBRARY["keratin"] and mirror.n2 is dispersion.LIBRARY["melanin"]


@pytest.mark.parametrize("name", sorted(PUBLISHED_PEAKS))
def test_jewel_beetle_peaks_where_published(name):
    peak, tolerance = PUBLISHED_PEAKS[name]
    mirror = natural_mirror(dict(SPECIMENS[name].resolve()), {})
    wavelengths = np.arange(400.0, 800.0, 2.0)
    R = mirror_spectrum(mirror, wavelengths, [0.0, 45.0])["R"]
    assert abs(wavelengths[R[0].argmax()] - peak) <= tolerance
    assert wavelengths[R[1].argmax()] < wavelengths[R[0].argmax()] - 30.0  # the published shift to the blue


def test_parotia_period_meets_the_measured_infrared_peak():
    """The derived layer count aside, the ~200 nm layers put the first order at the measured ~1.3 um (Bragg)."""
    mirror = natural_mirror(dict(SPECIMENS["parotia_lawesii_occipital"].resolve()), {})
    n1, n2 = (d.real_at(1300.0) for d in (mirror.n1, mirror.n2))
    first_order = 2.0 * (n1 * mirror.d1 + n2 * mirror.d2)
    assert abs(first_order - 1300.0) < 0.05 * 1300.0
    # Melanin absorbs: the barbule's R + A stay within 1 and A is large in the blue.
    out = mirror_spectrum(mirror, np.array([400.0, 600.0]), [0.0])
    assert np.all(out["R"] + out["T"] <= 1.0 + 1e-12) and out["A"][0, 0] > 0.3


def test_presets_list_their_citation():
    run = run_cli("presets", "bragg_mirror", "--json", cwd=REPO_ROOT)
    assert run.returncode == 0, run.stderr
    rows = {row["name"]: row for row in json.loads(run.stdout)}
    assert rows["chrysochroa_fulgidissima_green"]["citation"].startswith("Stavenga")
    assert "citation" not in rows["figure3"]


def test_empty_citation_is_one_line(tmp_path):
    (tmp_path / "presets").mkdir()
    (tmp_path / "bragg_mirror.brd").write_text((REPO_ROOT / "shaders" / "bragg_mirror.brd").read_text())
    (tmp_path / "presets" / "bragg_mirror.toml").write_text(
        'material = "bragg_mirror.brd"\n[x]\nfigure = "f"\ndescription = "d"\ncitation = ""\nn1 = 1.2\n')
    with pytest.raises(PresetError) as error:
        load_presets(tmp_path / "presets" / "bragg_mirror.toml")
    assert error.value.line == 5 and "citation" in str(error.value)


def test_natural_mirror_is_the_papers_mirror_with_more():
    mirror = NaturalMirror(n1=1.5, n2=dispersion.LIBRARY["chitin"], Lambda=200.0, delta=0.3, N=4, k2=0.1)
    assert isinstance(mirror, BraggMirror) and (mirror.d1, mirror.d2) == pytest.approx((60.0, 140.0))


@pytest.mark.parametrize("args", [("--set", "nh=melanin"), ("--set", "medium_nh=4")])
def test_absorbing_host_is_one_line_naming_nh(args):
    for command in (("spectrum", "bragg_mirror"), ("render", "bragg_mirror", "--view", "gradient", "--engine", "numpy",
                                                    "--out", "unused.png")):
        line = one_line_error(run_cli(*command, *args, cwd=REPO_ROOT))
        assert "'nh'" in line and "melanin absorbs" in line and "bragg_mirror" in line
    assert host_problem({"nh": 1.0, "medium_nh": 0}) is None
    assert host_problem({"nh": 1.0, "medium_nh": 2}) is None  # chitin: lossless


def test_brdf_export_inlines_the_specimens_exact_table():
    """The .brdf file bakes the natural table (dispersion and absorption inlined as colours) for its values."""
    from explorer.materials.export_brdf import brdf_text, material_tables
    from explorer.physics.natural import natural_rgb_table

    preset = SPECIMENS["parotia_lawesii_occipital"]
    values = preset.resolve()
    tables = material_tables(preset.material, values)
    mirror = natural_mirror(dict(values), {})
    np.testing.assert_array_equal(tables["bragg_table"].reshape(-1, 3), natural_rgb_table(mirror))
    text = brdf_text(preset.material, values)
    assert "medium_n1 = 3, medium_n2 = 4" in text and "k1 = 0, k2 = 0, sigma = 0" in text


def test_textured_view_refuses_natural_layers_in_one_line():
    line = one_line_error(run_cli("render", "bragg_mirror", "--view", "textured", "--set", "n2=chitin", "--engine", "numpy",
                                  "--out", "unused.png", cwd=REPO_ROOT))
    assert "textured view" in line and "sigma" in line


def test_accuracy_presets_leave_out_natural_mirrors():
    """The approximations' table measures the paper's mirrors; a specimen with media shows the exact table anyway."""
    from explorer.cli.accuracy import preset_mirrors

    sources = {source for entry in preset_mirrors([PRESETS]) for source in entry.sources}
    assert "chrysochroa_fulgidissima_green" in sources and "figure3" in sources
    assert not {"parotia_lawesii_occipital", "glossy_black_barbule"} & sources
