"""
Painting with structural colour (``design --target-image``, explorer.design.paint): a 2-worker local Dask cluster
designs a 16 x 16 image back to maps whose colours (``render --maps``) match it, a second run resumes from the cache,
unreachable colours are flagged and masked pixels skipped, and bad images get one-line errors.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from PIL import Image

from conftest import one_line_error, run_cli

from explorer.materials.models import bragg_converged_rgb
from explorer.physics.colorimetry import delta_E_2000

pytest.importorskip("distributed")

ANGLES = (0.0, 45.0)
#: The material's defaults (n1 = 1, n2 = 1.5, delta = 0.5, N = 20, no host): only Lambda is designed, which keeps the
#: searches to a second or two each.
DEFAULTS = dict(n1=1.0, n2=1.5, nh=0.0, delta=0.5, N=20)
#: A painted structure's colour against tmm's and colour-science's (tests/test_design_independent.py's integral,
#: 0.5 nm trapezoids): its 20 cells' fringes are narrower than that design test's stacks (measured 0.022).
INDEPENDENT_DELTA_E = 0.05


def _colours(Lambda: float) -> np.ndarray:
    return bragg_converged_rgb({**DEFAULTS, "Lambda": Lambda}, np.cos(np.radians(ANGLES)))


def _two_regions(tmp_path, size=16):
    a, b = _colours(180.0), _colours(240.0)
    image = np.zeros((2, size, size, 3))
    image[:, :, : size // 2] = a[:, None, None]
    image[:, :, size // 2 :] = b[:, None, None]
    paths = []
    for k, theta in enumerate(ANGLES):
        path = tmp_path / f"target_{theta:g}.npy"
        np.save(path, image[k].astype(np.float32))
        paths.append(path)
    return image, paths


def test_a_two_worker_cluster_paints_a_16_pixel_image_that_renders_back(tmp_path):
    image, (first, second) = _two_regions(tmp_path)
    out = tmp_path / "maps"
    args = ("design", "bragg_mirror", "--target-image", first, "--target-image-2", second, "--free", "Lambda",
            "--out-maps", out, "--workers", "2", "--seed", "3", "--tries", "1")
    run = run_cli(*args)
    assert run.returncode == 0, run.stderr
    assert "2 Dask workers (local)" in run.stderr
    for name in ("Lambda.exr", "params.json", "delta_e_0.exr", "delta_e_45.exr", "unreachable.png", "report.json"):
        assert (out / name).is_file(), name
    assert not (out / "N.exr").exists()  # fixed: in params.json
    params = json.loads((out / "params.json").read_text())
    assert params["free"] == ["Lambda"] and params["fixed"]["N"] == 20 and params["angles_deg"] == list(ANGLES)
    report = json.loads((out / "report.json").read_text())
    assert report["pixels"] == 256 and report["colours"] == 2 and report["within_1_at_every_angle"] == 1.0
    assert not np.asarray(Image.open(out / "unreachable.png")).any()
    from explorer.views.maps import read_maps

    _, maps = read_maps(out)
    assert maps["Lambda"].shape == (16, 16)
    np.testing.assert_allclose(maps["Lambda"][:, :8], 180.0, rtol=0.02)
    np.testing.assert_allclose(maps["Lambda"][:, 8:], 240.0, rtol=0.02)
    # The maps render back to the targets (render --maps, the same forward model the independent check would use).
    for k, theta in enumerate(ANGLES):
        rendered = tmp_path / f"again_{theta:g}.npy"
        again = run_cli("render", "bragg_mirror", "--maps", out, "--view", "textured", "--engine", "numpy", "--theta", theta, "--out", rendered)
        assert again.returncode == 0, again.stderr
        assert np.max(delta_E_2000(np.load(rendered).astype(float), image[k])) < 1.0
    # A second run reads every task from the cache: the same maps.
    resumed = run_cli(*args)
    assert resumed.returncode == 0, resumed.stderr
    assert "designs: 2 tasks (2 from the cache)" in resumed.stderr
    _, maps_again = read_maps(out)
    np.testing.assert_array_equal(maps_again["Lambda"], maps["Lambda"])


def test_unreachable_colours_are_flagged_and_masked_pixels_skipped():
    from explorer.design import ranges_of
    from explorer.design.paint import PaintTargets, paint
    from explorer.cli.design import load

    material = load("bragg_mirror")
    reachable = _colours(200.0)
    red = np.array([1.0, 0.0, 0.0])  # saturated sRGB red at both angles: no mirror keeps it at 45 degrees
    rgb = np.zeros((2, 3, 4, 3))
    rgb[:, :, :2] = red
    rgb[:, :, 2:] = reachable[:, None, None]
    mask = np.ones((3, 4), bool)
    mask[0] = False  # alpha 0: skipped
    targets = PaintTargets(ANGLES, rgb, np.zeros(rgb.shape, np.int8), mask)
    # Without a client every task runs here, in turn (the same functions the workers run).
    result = paint("bragg_mirror", ranges_of(material), DEFAULTS, targets, seed=0, client=None, tries=1, rescue_tries=1)
    expected = np.zeros((3, 4), bool)
    expected[1:, :2] = True
    np.testing.assert_array_equal(result.unreachable, expected)
    assert np.all(np.isnan(result.maps["Lambda"][0])) and np.all(np.isnan(result.delta_e[:, 0]))
    assert np.all(result.delta_e[:, 1:, 2:] < 1.0)
    assert np.all(np.max(result.delta_e[:, 1:, :2], axis=0) > 2.0)
    # An independent check of a written structure: tmm's spectrum and colour-science's colour (tests/test_design_independent.py)
    # against the colour the result reports and the target.
    import colour
    from test_design_independent import XY_E, lab_of_rgb, mirror_layers, tmm_unpolarised, xyz_of

    structure = {**DEFAULTS, "Lambda": float(result.maps["Lambda"][1, 2])}
    indices, thicknesses = mirror_layers(structure)
    for k, theta in enumerate(ANGLES):
        lab = colour.XYZ_to_Lab(xyz_of(tmm_unpolarised(indices, thicknesses, theta)), XY_E)
        assert colour.delta_E(lab, lab_of_rgb(result.achieved[k, 1, 2]), method="CIE 2000") <= INDEPENDENT_DELTA_E
        assert colour.delta_E(lab, lab_of_rgb(reachable[k]), method="CIE 2000") < 1.0


def test_a_file_that_is_not_an_image_is_one_line(tmp_path):
    bad = tmp_path / "notes.png"
    bad.write_text("not an image\n")
    run = run_cli("design", "bragg_mirror", "--target-image", bad, "--out-maps", tmp_path / "maps")
    assert "notes.png" in one_line_error(run)


def test_targets_of_different_sizes_are_one_line(tmp_path):
    np.save(tmp_path / "a.npy", np.full((8, 8, 3), 0.2, np.float32))
    np.save(tmp_path / "b.npy", np.full((8, 6, 3), 0.2, np.float32))
    run = run_cli("design", "bragg_mirror", "--target-image", tmp_path / "a.npy", "--target-image-2", tmp_path / "b.npy",
                  "--out-maps", tmp_path / "maps")
    line = one_line_error(run)
    assert "6x8" in line and "8x8" in line


def test_paint_options_need_a_target_image(tmp_path):
    run = run_cli("design", "bragg_mirror", "--target", "0:#3f9f4f", "--out-maps", tmp_path / "maps")
    assert "--target-image" in one_line_error(run)


def test_render_maps_of_a_folder_without_maps_is_one_line(tmp_path):
    run = run_cli("render", "bragg_mirror", "--maps", tmp_path, "--view", "textured", "--engine", "numpy", "--out", tmp_path / "x.npy")
    assert "params.json" in one_line_error(run)


def _row_model():
    from explorer.design import design_model, parameter_box, ranges_of
    from explorer.cli.design import load
    from explorer.design.pixels import RowModel

    model = design_model("bragg_mirror")
    material = load("bragg_mirror")
    defaults = material.resolve({})
    fixed = {name: float(defaults[name]) for name in model.parameters if name not in ("Lambda", "delta", "N")}
    free = [p for p in parameter_box(model, ranges_of(material)) if p.name not in fixed]
    return RowModel(model, free, fixed, np.cos(np.radians(ANGLES)))


def test_the_batched_polish_recovers_random_mirrors_colours_from_their_neighbours_structures():
    """
    Seeded random mirrors (Lambda, delta, N in the round trip's box): every one polished at once from a neighbouring
    structure (Lambda 1 % off, delta 0.01 off, N one off for a third of them), as a painted pixel starts from its
    neighbour's (0.5 to 9 CIEDE2000 away). The coarse colours are recovered: four in five below the RMS CIEDE2000 at
    which the polish walks counts, most of those that started on their own count below its tolerance; no row ends
    worse than it started.
    """
    from explorer.design.pixels import COUNT_WALK_DELTA_E, POLISH_TOLERANCE, polish_whole, residual_rows

    rows = _row_model()
    rng = np.random.default_rng(7)
    count = 48
    truth = {"Lambda": rng.uniform(150.0, 320.0, count), "delta": rng.uniform(0.3, 0.7, count), "N": rng.integers(6, 31, count).astype(float)}
    target = rows.rgb(rows.unit(truth))
    start = {"Lambda": truth["Lambda"] * (1.0 + 0.01 * rng.choice([-1.0, 1.0], count)), "delta": truth["delta"] + 0.01 * rng.choice([-1.0, 1.0], count),
             "N": truth["N"] + np.where(np.arange(count) % 3 == 0, 1.0, 0.0)}
    U0 = rows.unit(start)
    U, cost = polish_whole(rows, target, None, U0)
    before = np.sum(residual_rows(rows.rgb(U0), target, None) ** 2, axis=1)
    rms = np.sqrt(cost / len(ANGLES))
    assert np.all(cost <= before + 1e-12)
    assert np.mean(rms < COUNT_WALK_DELTA_E) >= 0.8, np.sort(rms)[-10:]  # the rest: other basins (the neighbour rounds)
    assert np.median(rms[np.arange(count) % 3 != 0]) < POLISH_TOLERANCE
    # The costs are the rows' own: the colours of the polished structures, whole counts, say so.
    values = rows.values(U, whole=True)
    assert np.all(values["N"] == np.round(values["N"]))
    np.testing.assert_allclose(np.sum(residual_rows(rows.rgb(rows.unit(values)), target, None) ** 2, axis=1), cost, rtol=1e-9, atol=1e-12)


def test_the_polish_levels_hold_every_colour_once_coarse_grid_first():
    from explorer.design.paint import COARSEST_GRID, _levels

    side = 4 * COARSEST_GRID
    colours = np.arange(side * side).reshape(side, side) // 2  # pairs of pixels share a colour
    colours[0, 0] = -1  # masked
    possible = np.ones(colours.max() + 1, bool)
    possible[5] = False
    levels = _levels(colours, possible)
    held = np.concatenate([members for members, _ in levels])
    expected = np.setdiff1d(np.unique(colours[colours >= 0]), [5])
    np.testing.assert_array_equal(np.sort(held), expected)
    assert len(levels) == 3 and len(levels[0][0]) == COARSEST_GRID**2 - 1  # the masked corner's colour comes later
    for members, where in levels:
        assert all(colours[y, x] == c for c, (y, x) in zip(members, where))


def test_a_start_one_cell_off_finds_its_count_without_walking():
    """
    Seeded random mirrors started from their own structure with one cell more or fewer (a smooth map's neighbour):
    those the held polish cannot fit move by the step of one cell either way, with no free walk of the counts.
    """
    from explorer.design.pixels import COUNT_WALK_DELTA_E, polish_rows, polish_whole

    rows = _row_model()
    rng = np.random.default_rng(11)
    count = 16
    truth = {"Lambda": rng.uniform(150.0, 320.0, count), "delta": rng.uniform(0.3, 0.7, count), "N": rng.integers(8, 29, count).astype(float)}
    target = rows.rgb(rows.unit(truth))
    U0 = rows.unit({**truth, "N": truth["N"] + rng.choice([-1.0, 1.0], count)})
    _, held_cost = polish_rows(rows, target, None, U0, held=[p.integer for p in rows.free])
    U, cost = polish_whole(rows, target, None, U0, walk=False)
    assert np.mean(np.sqrt(cost / len(ANGLES)) < COUNT_WALK_DELTA_E) >= 0.9, np.sqrt(cost / len(ANGLES))
    assert np.all(cost <= held_cost + 1e-12)
    # Other counts fit too (Lambda and delta make up for a cell), but the rows the held count left poor moved.
    stepped = held_cost > COUNT_WALK_DELTA_E**2 * len(ANGLES)
    assert stepped.any() and np.all(cost[stepped] < held_cost[stepped]), (held_cost, cost)


def test_a_neighbour_round_never_repeats_a_start():
    from explorer.design.paint import _candidates

    U = np.array([[0.1, 0.2, 0.3], [0.4, 0.5, 0.6], [0.7, 0.8, 0.9]])
    cost = np.array([5.0, 1.0, 0.5])
    pairs = {0: {1, 2}, 1: {0}, 2: {0}}
    labels, centre_U, tried = np.zeros(3, dtype=np.int64), U[2:], {}
    first = _candidates([0], cost, pairs, labels, centre_U, U, tried)
    assert [list(s) for s in first[0]] == [list(U[2]), list(U[1])]  # the better neighbours, best first
    assert _candidates([0], cost, pairs, labels, centre_U, U, tried)[0] == []  # nothing new: no second polish
    U[1] += 0.05  # a neighbour improved: its new structure is a new start
    assert [list(s) for s in _candidates([0], cost, pairs, labels, centre_U, U, tried)[0]] == [list(U[1])]


def test_a_two_worker_cluster_paints_a_film_image_that_renders_back(tmp_path):
    """
    ``design`` of a thin film (the film's thickness free) on a 2-worker local cluster, from an 8 x 8 image of two
    films' colours at 0 and 45 degrees, then ``render --maps`` of the folder: the maps render back to the targets.
    """
    from explorer.design.forward import design_model
    from explorer.views.maps import read_maps

    model = design_model("thin_film")
    fixed = {"eta1": 1.0, "eta2": 1.33, "eta3": 1.5, "kappa3": 0.0}
    size, thicknesses = 8, (300.0, 450.0)
    colours = [model.converged({**fixed, "d": d}, np.cos(np.radians(ANGLES)), final=True) for d in thicknesses]
    image = np.zeros((2, size, size, 3))
    image[:, :, : size // 2], image[:, :, size // 2 :] = colours[0][:, None, None], colours[1][:, None, None]
    paths = []
    for k, theta in enumerate(ANGLES):
        paths.append(tmp_path / f"film_{theta:g}.npy")
        np.save(paths[-1], image[k].astype(np.float32))
    out = tmp_path / "film_maps"
    run = run_cli("design", "thin_film", "--target-image", paths[0], "--target-image-2", paths[1], "--free", "d",
                  *[a for name, value in fixed.items() for a in ("--fix", f"{name}={value}")],
                  "--out-maps", out, "--workers", "2", "--seed", "1", "--tries", "1")
    assert run.returncode == 0, run.stderr
    assert "2 Dask workers (local)" in run.stderr
    report = json.loads((out / "report.json").read_text())
    assert report["pixels"] == size * size and report["colours"] == 2 and report["within_1_at_every_angle"] == 1.0
    _, maps = read_maps(out)
    assert set(maps) == {"d"} and maps["d"].shape == (size, size)
    for k, theta in enumerate(ANGLES):
        rendered = tmp_path / f"film_again_{theta:g}.npy"
        again = run_cli("render", "thin_film", "--maps", out, "--view", "textured", "--engine", "numpy", "--theta", theta, "--out", rendered)
        assert again.returncode == 0, again.stderr
        assert np.max(delta_E_2000(np.load(rendered).astype(float), image[k])) < 1.0


def test_the_local_clusters_workers_run_without_dasks_malloc_trim_threshold():
    # Dask sets MALLOC_TRIM_THRESHOLD_ in each worker it spawns; it turns glibc's adaptive mmap threshold off, which
    # made the batched models' large temporaries cost ~1.5 times the CPU (explorer.design.paint.WORKER_ENVIRONMENT_UNSET).
    import os

    import dask
    from distributed import Client

    from explorer.design.paint import WORKER_ENVIRONMENT_UNSET, local_cluster

    with local_cluster(1) as cluster, Client(cluster) as client:
        seen = client.submit(lambda names: {n: os.environ.get(n) for n in names}, WORKER_ENVIRONMENT_UNSET).result()
    assert seen == {name: None for name in WORKER_ENVIRONMENT_UNSET}
    # Dask's own default is left as it was, for the clusters a user starts.
    assert dask.config.get("distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_") is not None
