"""The numpy twins register themselves (explorer/materials/twins.py), one per ``# model:`` name."""

from __future__ import annotations

import pytest

from conftest import REPO_ROOT
from explorer.materials.brd import load_material
from explorer.materials.models import MODELS, model_for
from explorer.materials.twins import TWINS, Twin, twin


@pytest.mark.parametrize("path", sorted((REPO_ROOT / "shaders").glob("*.brd")), ids=lambda p: p.stem)
def test_every_shipped_material_has_a_registered_twin(path):
    material = load_material(path)
    assert material.model in TWINS and MODELS is TWINS
    model = model_for(material, material.resolve())
    assert isinstance(model, Twin) and type(model) is TWINS[material.model]


def test_registration_refuses_a_second_class_and_a_nameless_one():
    class Impostor:
        name = "bragg_mirror"

        def reflectance(self, c): ...
        def brdf(self, L, V, N, X, Y): ...
        def textures(self): ...

    with pytest.raises(ValueError, match="registered twice"):
        twin(Impostor)
    with pytest.raises(TypeError, match="name"):
        twin(type("Nameless", (), {}))
    with pytest.raises(TypeError, match="brdf"):
        twin(type("Partial", (), {"name": "partial_twin", "reflectance": lambda self, c: c, "textures": lambda self: {}}))
    assert "partial_twin" not in TWINS


@pytest.mark.parametrize("path", sorted((REPO_ROOT / "shaders").glob("*.brd")), ids=lambda p: p.stem)
def test_a_twins_sampling_lobes_are_the_shaders(path):
    """A twin that declares ``sampling_lobes`` (the env view's numpy twin and Mitsuba sample by them) has the shader's
    hook too, and the other way round: otherwise the GL env view samples another density than its twins."""
    material = load_material(path)
    model = model_for(material, material.resolve())
    assert callable(getattr(model, "sampling_lobes", None)) == ("HAS_SAMPLING_LOBES" in material.shader), material.model
