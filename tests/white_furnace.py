"""
The white furnace of a rough Bragg layer with multiple scattering, for every material that has one (the layer,
test_compensation_fade.py; the stack's layers, test_multiscatter.py): with facets that reflect everything (the
model's documented test hook ``facet_reflectance_override``) over a black base, the directional albedo stays
within [0.99, 1.005] in numpy and in GL, where single scattering (Eq. 17 / Eq. 34 as published) loses light.
"""

from __future__ import annotations

import numpy as np

from explorer.materials.models import model_for
from explorer.views.albedo import albedo_gl, albedo_numpy

#: The angles (deg) of the furnace's albedos, and the roughnesses where single scattering loses most.
FURNACE_THETA = (0.0, 45.0, 70.0)
FURNACE_ALPHAS = (0.6, 1.0)
#: What the albedo may be: all the light, to float and quadrature error.
FURNACE_LOW, FURNACE_HIGH = 0.99, 1.005


def white_facets(monkeypatch, model_class) -> None:
    """Facets that reflect everything, for the models of ``model_class`` (undone by ``monkeypatch``)."""
    monkeypatch.setattr(model_class, "facet_reflectance_override", 1.0)


def assert_white_furnace_numpy(material, values: dict) -> None:
    """The numpy twin keeps all the light; without the compensation it loses a fifth or more at 45 deg."""
    albedo = albedo_numpy(model_for(material, values), FURNACE_THETA)
    assert np.all(albedo >= FURNACE_LOW) and np.all(albedo <= FURNACE_HIGH), albedo
    single = albedo_numpy(model_for(material, {**values, "multiple_scattering": False}), (45.0,))
    assert np.all(single < 0.8), single  # what the compensation puts back


def assert_white_furnace_gl(renderer, material, values: dict) -> None:
    """The GL albedo (the albedo view's integral) keeps all the light too."""
    albedo = albedo_gl(material, values, (0.0, 70.0), renderer, size=256, model=model_for(material, values))
    assert np.all(albedo >= FURNACE_LOW) and np.all(albedo <= FURNACE_HIGH), albedo
