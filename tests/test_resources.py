"""explorer.resources: where the shipped data is found, and built-in materials by name."""

from __future__ import annotations

import pytest

from conftest import REPO_ROOT

from explorer import resources


def test_a_checkout_uses_its_own_top_level_folders():
    assert resources.CHECKOUT_ROOT == REPO_ROOT
    assert resources.SHADER_DIR == REPO_ROOT / "shaders" and resources.LUT_DIR == REPO_ROOT / "luts"
    for path in (resources.DEFAULT_MATERIAL, resources.DEFAULT_TEXTURE, resources.DEFAULT_ENVIRONMENT):
        assert path.is_file() and path.is_relative_to(resources.SHADER_DIR)


def test_every_module_takes_its_paths_from_resources():
    """One source of truth: no other module computes the repository root from its own file."""
    offenders = [path.name for path in (REPO_ROOT / "explorer").glob("*.py")
                 if path.name != "resources.py" and "__file__).resolve().parent.parent" in path.read_text()]
    assert offenders == []


def test_builtin_materials_are_the_shipped_brd_files():
    assert sorted(resources.builtin_materials()) == sorted(p.stem for p in (REPO_ROOT / "shaders").glob("*.brd"))


def test_material_path_of_a_bare_name(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    mirror = resources.SHADER_DIR / "bragg_mirror.brd"
    assert resources.material_path("bragg_mirror") == mirror
    assert resources.material_path("bragg_mirror.brd") == mirror
    # A file of that name in the working folder wins; a path is taken as it is, existing or not.
    (tmp_path / "bragg_mirror.brd").write_text("")
    assert resources.material_path("bragg_mirror.brd").resolve() == (tmp_path / "bragg_mirror.brd").resolve()
    assert str(resources.material_path("sub/none.brd")) == "sub/none.brd"
    for name in ("no_such", "bragg_mirror.brdf", "thin_film.txt"):
        with pytest.raises(resources.UnknownMaterial) as caught:
            resources.material_path(name)
        message = str(caught.value)
        assert message.startswith(f"{name}: ") and "\n" not in message
        assert all(stem in message for stem in resources.builtin_materials())


def test_display_path(tmp_path, monkeypatch):
    mirror = resources.SHADER_DIR / "bragg_mirror.brd"
    monkeypatch.chdir(REPO_ROOT)
    assert resources.display_path(mirror) == "shaders/bragg_mirror.brd"
    monkeypatch.chdir(tmp_path)
    assert resources.display_path(mirror) == "bragg_mirror"  # what render accepts from here
    other = REPO_ROOT / "tests" / "data" / "brdf" / "lambert.brdf"
    assert resources.display_path(other) == str(other)
