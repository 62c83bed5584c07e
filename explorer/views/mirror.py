"""
A smooth mirror (a Dirac reflector: a material that declares ``MIRROR_ONLY``, its numpy twin ``mirror_only``)
in the ``lit`` view, in numpy: the twin of ``shaders/views/lit.glsl``'s mirror branch.

Under one directional light a Dirac reflection is black but where the mirror direction meets the light
exactly (no pixel, at any resolution). A mirror ball in the lit view therefore shows what a smooth mirror
shows under the env view (``mirror_reflection(V, N) L_e(reflect(-V, N))``, Eq. 34's f_r,0 for a coating;
the Bragg mirror's ``R(theta)``), under the env view's environment, plus the directional light as a small
glint (:func:`light_glint`): the light is a disc of angular radius :data:`GLINT_RADIUS_DEGREES` whose
irradiance on a surface facing it is 1, the lit view's unit irradiance. Rough materials are unchanged.

References
----------
Fourneau, Pacanowski, Barla (2024), Eq. 34 (the coating's Dirac f_r,0) and Section 3 (the smooth mirror's
reflectance R(theta) under an environment).
"""

from __future__ import annotations

import math
import re

import numpy as np

#: The light's angular radius in the mirror (degrees): a few pixels of a 256² sphere, where it moves with the light.
GLINT_RADIUS_DEGREES = 3.0
#: sin^2 of that radius (the shader's uniform ``glint_sin2``).
GLINT_SIN2 = math.sin(math.radians(GLINT_RADIUS_DEGREES)) ** 2
#: The glint's peak radiance, ``4 / (pi sin^2 rho)``: its irradiance on a surface facing the light is exactly 1
#: (:func:`light_glint`; the shader's uniform ``glint_peak``).
GLINT_PEAK = 4.0 / (math.pi * GLINT_SIN2)

_MIRROR_ONLY = re.compile(r"^\s*#\s*define\s+MIRROR_ONLY\b", re.M)


def is_mirror_only(material) -> bool:
    """Whether a material (:class:`explorer.materials.brd.Material`) is a Dirac reflector: its shader ``#define``\\ s ``MIRROR_ONLY``."""
    return bool(_MIRROR_ONLY.search(getattr(material, "shader", "") or ""))


#: What a BRDF plot's values are: a density per steradian, or for a smooth mirror (a Dirac, which has none) the
#: weight of its reflection, its reflectance at the half vector. The app's Polar and Slice and the CLI's charts say so.
BRDF_QUANTITY = "BRDF (1/sr)"
MIRROR_QUANTITY = "reflectance R(theta_d)"


def plotted_quantity(mirrors) -> str:
    """The quantity a BRDF plot of some materials shows; ``mirrors``: :func:`is_mirror_only` of each."""
    mirrors = list(mirrors)
    if mirrors and all(mirrors):
        return MIRROR_QUANTITY
    if not any(mirrors):
        return BRDF_QUANTITY
    return f"{BRDF_QUANTITY}; a smooth mirror's {MIRROR_QUANTITY}"


def light_glint(reflected, light) -> np.ndarray:
    """
    The directional light seen in a mirror: radiance ``GLINT_PEAK t^3``, ``t = 1 - |r x l|^2 / sin^2 rho``,
    toward unit directions ``reflected`` within :data:`GLINT_RADIUS_DEGREES` of the unit ``light`` (0 elsewhere).

    Its irradiance on a surface facing the light is ``int_0^rho GLINT_PEAK t^3 cos theta 2 pi sin theta d theta
    = pi sin^2 rho / 4 x GLINT_PEAK = 1`` (substitute ``x = sin^2 theta``). The profile is in ``sin^2`` (a
    cross product), not ``1 - cos``: float32 keeps its digits near the centre, and its cube falls to 0 at the
    edge with a zero slope, so the GLSL and numpy twins agree to the views' relative tolerance.
    """
    r = np.asarray(reflected, dtype=np.float64)
    l = np.broadcast_to(np.asarray(light, dtype=np.float64), r.shape)
    c = np.cross(r, l)
    t = 1.0 - np.sum(c * c, axis=-1) / GLINT_SIN2
    toward = np.sum(r * l, axis=-1) > 0.0
    return np.where(toward & (t > 0.0), GLINT_PEAK * np.maximum(t, 0.0) ** 3, 0.0)


def mirror_lit(model, V, N, light, environment) -> np.ndarray:
    """
    The lit view of a smooth mirror at unit ``V``, ``N`` (``(P, 3)``, the view's float32 geometry): ``(P, 3)``
    float64, ``mirror_reflection(V, N) (L_e(r) + light_glint(r, light))`` with ``r = reflect(-V, N)``
    (``environment``: an :class:`explorer.views.env.EnvironmentMap`, turned as it is).
    """
    v, n = np.asarray(V, dtype=np.float64), np.asarray(N, dtype=np.float64)
    reflected = 2.0 * np.sum(v * n, axis=-1, keepdims=True) * n - v
    incoming = environment.radiance(reflected) + light_glint(reflected, light)[..., None]
    weight = np.array(model.mirror_reflection(v, n), dtype=np.float64)
    weight[~np.isfinite(weight)] = 0.0  # the views' rule: a non-finite channel counts as 0
    return weight * incoming
