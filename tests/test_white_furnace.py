"""
The white furnace of multiple scattering, for every twin that compensates it (the registry's
:class:`explorer.materials.models.CompensatedTwin` subclasses: the rough layer and the stack's layers): with facets
that reflect everything (the twins' documented test hook ``facet_reflectance_override``: the same code path in numpy
and GL) over a black base, one rough layer keeps its directional albedo within [0.99, 1.005] at theta <= 70 deg,
where single scattering (Eq. 17 / Eq. 34 as published) loses a fifth or more. The random walk's furnace of the
layer is in test_compensation_fade.py.
"""

from __future__ import annotations

import numpy as np
import pytest

from explorer.materials.brd import load_material
from explorer.materials.models import BraggLayerModel, BraggStackModel, CompensatedTwin, model_for
from explorer.materials.twins import TWINS
from explorer.resources import SHADER_DIR
from explorer.views.albedo import albedo_gl, albedo_numpy

#: The angles (deg) of the furnace's albedos, and the roughnesses where single scattering loses most.
FURNACE_THETA = (0.0, 45.0, 70.0)
FURNACE_ALPHAS = (0.6, 1.0)
#: What the albedo may be: all the light, to float and quadrature error.
FURNACE_LOW, FURNACE_HIGH = 0.99, 1.005
#: Per compensating twin: one rough layer of 10 cells over a black base with the compensation on, and the name of
#: that layer's roughness.
FURNACES = {
    BraggLayerModel: ({"rho_d": 0.0, "N": 10, "method": 3, "multiple_scattering": 1}, "alpha"),
    BraggStackModel: ({"layers": 1, "nh": 1.0, "rho_d": 0.0, "N_1": 10, "multiple_scattering": 1}, "alpha_1"),
}
CASES = [pytest.param(cls, alpha, id=f"{cls.name}-alpha={alpha:g}") for cls in FURNACES for alpha in FURNACE_ALPHAS]


def white_furnace(monkeypatch, cls, alpha: float):
    """``cls``'s material and furnace values at roughness ``alpha``, its facets white for this test."""
    monkeypatch.setattr(cls, "facet_reflectance_override", 1.0)
    material = load_material(SHADER_DIR / f"{cls.name}.brd")
    values, roughness = FURNACES[cls]
    return material, material.resolve({**values, roughness: alpha})


def test_every_compensating_twin_has_a_furnace():
    assert set(FURNACES) == {cls for cls in TWINS.values() if issubclass(cls, CompensatedTwin)}


@pytest.mark.parametrize("cls, alpha", CASES)
def test_white_furnace_numpy(monkeypatch, cls, alpha):
    material, values = white_furnace(monkeypatch, cls, alpha)
    albedo = albedo_numpy(model_for(material, values), FURNACE_THETA)
    assert np.all(albedo >= FURNACE_LOW) and np.all(albedo <= FURNACE_HIGH), albedo
    single = albedo_numpy(model_for(material, {**values, "multiple_scattering": False}), (45.0,))
    assert np.all(single < 0.8), single  # what the compensation puts back


@pytest.mark.gl
@pytest.mark.parametrize("cls, alpha", CASES)
def test_white_furnace_gl(gl_renderer, monkeypatch, cls, alpha):
    material, values = white_furnace(monkeypatch, cls, alpha)
    albedo = albedo_gl(material, values, (0.0, 70.0), gl_renderer, size=256, model=model_for(material, values))
    assert np.all(albedo >= FURNACE_LOW) and np.all(albedo <= FURNACE_HIGH), albedo
