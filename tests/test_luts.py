"""The precomputed tables in luts/: up to date, regenerated when stale, and what Eq. 16 needs."""

from __future__ import annotations

import json
import shutil

import numpy as np
import pytest

from explorer.physics import colorimetry
from explorer.tables import luts

#: Sums of up to 471 CMF values against the cumulative table's differences.
CUMULATIVE_ATOL = 1e-12
#: A table regenerated on another machine (CPU, numpy, libm) against the committed one: sums of 471
#: products differ in their last bits (~1e-15 measured); the tables hold values of order 1.
REGENERATED_ATOL = 1e-12
NAMES = sorted(luts.TABLES)


@pytest.fixture
def lut_copy(tmp_path):
    """A private copy of the committed luts/ directory."""
    directory = tmp_path / "luts"
    shutil.copytree(luts.LUT_DIR, directory)
    return directory


def committed(name: str) -> np.ndarray:
    return np.load(luts.LUT_DIR / f"{name}.npy")


@pytest.mark.parametrize("name", NAMES)
def test_committed_tables_are_up_to_date(name):
    assert luts.staleness(name) is None
    table = committed(name)
    assert table.dtype == np.float64
    manifest = json.loads((luts.LUT_DIR / luts.MANIFEST).read_text())["tables"][name]
    assert list(table.shape) == manifest["shape"] == luts.TABLES[name].spec["shape"]
    assert manifest["source"] == luts.TABLES[name].source()  # the registering module's line
    # And they are what the generator writes today, to rounding: never bit for bit across machines.
    np.testing.assert_allclose(table, luts.TABLES[name].generate(), rtol=0, atol=REGENERATED_ATOL)


def test_committed_tables_content():
    cmf = committed("cmf_1nm")
    np.testing.assert_allclose(cmf, colorimetry.colour_matching_functions(), rtol=0, atol=REGENERATED_ATOL)
    cumulative = committed("cmf_cumulative")
    np.testing.assert_array_equal(cumulative[0], 0.0)
    np.testing.assert_allclose(cumulative[1:], np.cumsum(cmf, axis=0), rtol=0, atol=CUMULATIVE_ATOL)
    np.testing.assert_allclose(cumulative[-1], colorimetry.white_xyz(), rtol=0, atol=CUMULATIVE_ATOL)
    assert (np.diff(cumulative, axis=0) >= 0).all()  # the CMFs are non-negative


def _alter_npy(path):
    table = np.load(path)
    table[len(table) // 2, 1] += 1e-3
    np.save(path, table)


def _alter_spec(directory, name):
    manifest_path = directory / luts.MANIFEST
    manifest = json.loads(manifest_path.read_text())
    manifest["tables"][name]["resolution_nm"] = 5.0
    manifest_path.write_text(json.dumps(manifest))


def _drop_entry(directory, name):
    manifest_path = directory / luts.MANIFEST
    manifest = json.loads(manifest_path.read_text())
    del manifest["tables"][name]
    manifest_path.write_text(json.dumps(manifest))


ALTERATIONS = {
    "altered npy": (lambda d, n: _alter_npy(d / f"{n}.npy"), "checksum mismatch"),
    "altered spec": (_alter_spec, "generated with other parameters"),
    "missing file": (lambda d, n: (d / f"{n}.npy").unlink(), "file missing"),
    "not in manifest": (_drop_entry, "not in the manifest"),
    "corrupt manifest": (lambda d, n: (d / luts.MANIFEST).write_text("{not json"), "not in the manifest"),
}


@pytest.mark.parametrize("name", NAMES)
@pytest.mark.parametrize("alteration", list(ALTERATIONS))
def test_stale_table_is_reported_and_regenerated(lut_copy, name, alteration):
    alter, reason = ALTERATIONS[alteration]
    alter(lut_copy, name)
    assert luts.staleness(name, lut_copy) == reason
    messages = []
    table = luts.load(name, lut_copy, log=messages.append)
    assert len(messages) == 1 and name in messages[0] and reason in messages[0]
    np.testing.assert_allclose(table, committed(name), rtol=0, atol=REGENERATED_ATOL)
    # Regenerated on disk, with a manifest entry that makes it current again.
    assert luts.staleness(name, lut_copy) is None
    np.testing.assert_array_equal(np.load(lut_copy / f"{name}.npy"), table)
    # Loading again uses it silently.
    assert luts.load(name, lut_copy, log=messages.append) is table and len(messages) == 1
    assert not table.flags.writeable


def test_untouched_copy_loads_silently(lut_copy):
    for name in NAMES:
        messages = []
        table = luts.load(name, lut_copy, log=messages.append)
        assert messages == []
        np.testing.assert_array_equal(table, committed(name))  # the same file, read back


def test_stale_table_in_unwritable_place_is_used_from_memory(tmp_path):
    """A directory that cannot be created (a file is in the way): generated in memory, with a message."""
    blocker = tmp_path / "file"
    blocker.write_text("")
    messages = []
    table = luts.load("cmf_cumulative", blocker / "luts", log=messages.append)
    assert len(messages) == 1 and "cmf_cumulative" in messages[0]
    np.testing.assert_allclose(table, committed("cmf_cumulative"), rtol=0, atol=REGENERATED_ATOL)


# --------------------------------------------------------------------------------------------------
# cmf_cumulative_at: Eq. 16


def test_cumulative_at_node_edges():
    white = colorimetry.white_xyz()
    first, last = colorimetry.CUMULATIVE_START, colorimetry.WAVELENGTH_MAX + 0.5
    np.testing.assert_array_equal(colorimetry.cmf_cumulative_at(first), 0.0)
    np.testing.assert_allclose(colorimetry.cmf_cumulative_at(last), white, rtol=0, atol=CUMULATIVE_ATOL)
    # Clamped outside, as an edge-clamped texture.
    np.testing.assert_array_equal(colorimetry.cmf_cumulative_at(np.array([100.0, 300.0])), 0.0)
    np.testing.assert_allclose(colorimetry.cmf_cumulative_at(np.array([900.0, 2e4])), [white, white], atol=CUMULATIVE_ATOL)
    # At every node: the sum of the bins below it.
    nodes = first + np.arange(colorimetry.WAVELENGTHS.size + 1)
    expected = np.concatenate([np.zeros((1, 3)), np.cumsum(colorimetry.colour_matching_functions(), axis=0)])
    np.testing.assert_allclose(colorimetry.cmf_cumulative_at(nodes), expected, rtol=0, atol=CUMULATIVE_ATOL)
    assert colorimetry.cmf_cumulative_at(np.zeros((4, 5))).shape == (4, 5, 3)


def box_integral(a: float, b: float) -> np.ndarray:
    """XYZ of a box spectrum (1 on [a, b] nm), by the overlap of [a, b] with each 1 nm bin."""
    w = colorimetry.WAVELENGTHS
    overlap = np.clip(np.minimum(b, w + 0.5) - np.maximum(a, w - 0.5), 0.0, 1.0)
    return overlap @ colorimetry.colour_matching_functions()


def test_box_spectrum_on_bin_edges_is_the_1nm_sum():
    rng = np.random.default_rng(13)
    for _ in range(50):
        a, b = np.sort(rng.integers(360, 831, size=2))
        lo, hi = a - 0.5, b + 0.5
        inside = (colorimetry.WAVELENGTHS >= a) & (colorimetry.WAVELENGTHS <= b)
        expected = colorimetry.spectrum_to_xyz(inside.astype(float))
        span = colorimetry.cmf_cumulative_at(hi) - colorimetry.cmf_cumulative_at(lo)
        np.testing.assert_allclose(span, expected, rtol=0, atol=CUMULATIVE_ATOL)


def test_box_spectrum_anywhere_is_the_overlap_sum():
    """Between nodes C is linear (CMFs constant over each 1 nm bin): partial bins count pro rata."""
    rng = np.random.default_rng(17)
    for _ in range(200):
        a, b = np.sort(rng.uniform(340.0, 850.0, size=2))
        span = colorimetry.cmf_cumulative_at(b) - colorimetry.cmf_cumulative_at(a)
        np.testing.assert_allclose(span, box_integral(a, b), rtol=0, atol=CUMULATIVE_ATOL)


def test_stale_shipped_table_is_regenerated_into_the_user_cache(tmp_path, monkeypatch):
    """The shipped tables are never written: a stale one is regenerated into the cache, then read from there."""
    shipped = tmp_path / "site-packages" / "luts"
    shutil.copytree(luts.LUT_DIR, shipped)
    expected = committed("cmf_1nm")
    monkeypatch.setattr(luts, "LUT_DIR", shipped)
    monkeypatch.setattr(luts, "_cache", {})
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))
    cache = tmp_path / "cache" / "bragg-explorer" / "luts"
    assert luts.cache_lut_dir() == cache
    _alter_npy(shipped / "cmf_1nm.npy")
    before = {p.name: p.read_bytes() for p in shipped.iterdir()}
    messages = []
    table = luts.load("cmf_1nm", log=messages.append)
    assert len(messages) == 1 and "checksum mismatch" in messages[0] and str(cache) in messages[0], messages
    np.testing.assert_allclose(table, expected, rtol=0, atol=REGENERATED_ATOL)
    assert {p.name: p.read_bytes() for p in shipped.iterdir()} == before  # untouched
    assert luts.staleness("cmf_1nm", cache) is None
    # A current shipped table is read from the installation, whatever the cache holds.
    assert luts.load("cmf_cumulative", log=messages.append) is not None and len(messages) == 1
    assert not (cache / "cmf_cumulative.npy").exists()
    # A later process (an empty memory cache) uses the cached table silently.
    monkeypatch.setattr(luts, "_cache", {})
    np.testing.assert_array_equal(luts.load("cmf_1nm", log=messages.append), table)
    assert len(messages) == 1


def test_xdg_cache_home_must_be_absolute(monkeypatch, tmp_path):
    from explorer import resources

    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    assert resources.cache_dir() == tmp_path / "bragg-explorer"
    monkeypatch.setenv("XDG_CACHE_HOME", "relative/cache")  # the XDG specification: ignored
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    assert resources.cache_dir() == tmp_path / "home" / ".cache" / "bragg-explorer"
