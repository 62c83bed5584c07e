"""
How far each RGB method of a Bragg mirror is from the converged spectral reference, for the current
parameters: the accuracy badge of the app's Parameters window and of ``render``'s note on stderr.

The reference is the tabulated method's converged table (:func:`explorer.physics.bragg.tabulated_rgb_table`:
converged spectra over ``cos theta``, cached per mirror, which the app builds anyway for method 3), read
at the gradient view's angles. Each method's colour there is compared with it by ΔE2000 (colour-science,
:func:`explorer.physics.colorimetry.delta_E_2000`): a method is *accurate* for these parameters when its
median over θ is at most :data:`ACCURACY_LIMIT`, the goal of Fourneau et al. (2024), Section 5 (Table 1's
ΔE2000 < 2, "not noticeable at a glance").

References
----------
Fourneau, Pacanowski, Barla (2024). Interactive Exploration of Vivid Material Iridescence using Bragg
Mirrors. Computer Graphics Forum 43(2). Section 3.2 (the approximations), Table 1.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Mapping

import numpy as np

from explorer.materials.methods import BraggMethod
from explorer.physics import bragg, colorimetry

#: A method is accurate for the current parameters when its median ΔE2000 over θ is at most this.
ACCURACY_LIMIT = 2.0
#: The gradient view's columns the badge compares: θ = 90° (i + 0.5) / W.
BADGE_WIDTH = 90
#: The methods' names (``shaders/bragg_mirror.brd``), and the order in which accurate ones are suggested:
#: the exact table first (one texture fetch per pixel), then the closed forms, the spectral sum last.
METHOD_NAMES = {int(m): m.label for m in BraggMethod}
SUGGESTION_ORDER = (3, 4, 2, 1, 0)


def gradient_cos_theta(width: int = BADGE_WIDTH) -> np.ndarray:
    """The gradient view's ``cos theta`` per column, ``theta = 90 deg (i + 0.5) / width``
    (:func:`explorer.views.geometry.view_cos_theta`, which rounds it to float32 as the shader does)."""
    return np.cos(0.5 * np.pi * (np.arange(width) + 0.5) / width)


def method_rgb(mirror: bragg.BraggMirror, method: int, cos_theta, s: int = 3, wavelength_step: float = 1.0,
               table: np.ndarray | None = None) -> np.ndarray:
    """What ``shaders/bragg_mirror.brd`` shows for ``method`` at ``cos_theta`` (the numpy twin's reflectance)."""
    compute = {
        BraggMethod.REFERENCE: lambda: bragg.reference_rgb(cos_theta, mirror, step=wavelength_step),
        BraggMethod.BASIC: lambda: bragg.approximate_rgb(cos_theta, mirror, 0),
        BraggMethod.SUBDIVIDED: lambda: bragg.approximate_rgb(cos_theta, mirror, s),
        BraggMethod.TABULATED: lambda: bragg.tabulated_rgb(bragg.tabulated_rgb_table(mirror) if table is None else table, cos_theta),
        BraggMethod.IMPROVED: lambda: bragg.approximate_rgb(cos_theta, mirror, s, variant="improved"),
    }.get(method)
    if compute is not None:
        return compute()
    raise ValueError(f"unknown method {method} (methods: {', '.join(f'{k} {v}' for k, v in METHOD_NAMES.items())})")


@dataclass(frozen=True)
class MethodAccuracy:
    """Median and maximum ΔE2000 over θ of one method against the converged reference."""

    method: int
    dE_median: float
    dE_max: float

    @property
    def name(self) -> str:
        return METHOD_NAMES[self.method]

    @property
    def accurate(self) -> bool:
        return self.dE_median <= ACCURACY_LIMIT

    def label(self) -> str:
        return f"{self.method} {self.name}"


@dataclass(frozen=True)
class AccuracyBadge:
    """The current method's accuracy for the current parameters, and the methods accurate there."""

    method: int
    methods: dict[int, MethodAccuracy]
    #: Absorbing, dispersive or disordered layers: the approximations' landmarks assume none, so every method
    #: shows the exact table (``shaders/bragg_mirror.brd``'s natural_structure()).
    natural: bool = False

    @property
    def current(self) -> MethodAccuracy:
        return self.methods[self.method]

    @property
    def accurate(self) -> bool:
        return self.current.accurate

    def accurate_methods(self) -> list[int]:
        """The methods accurate here, in :data:`SUGGESTION_ORDER`."""
        return [m for m in SUGGESTION_ORDER if m in self.methods and self.methods[m].accurate]

    def _alternatives(self) -> str:
        others = [m for m in self.accurate_methods() if m != self.method]
        return ", ".join(f"{self.methods[m].label()} ({self.methods[m].dE_median:.1f})" for m in others) or "none"

    def text(self) -> str:
        """One line for the app: the current method's ΔE2000 and, when it is off, the accurate methods."""
        if self.natural:
            return f"natural layers (k, media, sigma): every method shows the exact table ({METHOD_NAMES[3]}, method 3)"
        c = self.current
        head = f"ΔE2000 vs converged: median {c.dE_median:.1f}, max {c.dE_max:.1f}"
        if c.accurate:
            return f"{head}: accurate (≤ {ACCURACY_LIMIT:g})"
        return f"{head}: OFF (> {ACCURACY_LIMIT:g}); accurate here: {self._alternatives()}"

    def note(self) -> str | None:
        """``render``'s one-line note when the current method is off (None when it is accurate)."""
        if self.accurate:
            return None
        c = self.current
        return (f"method {c.label()} is off here: median ΔE2000 {c.dE_median:.1f} (max {c.dE_max:.1f}) against the "
                f"converged reference over the gradient's angles; accurate here: {self._alternatives()}")


def mirror_accuracy(mirror: bragg.BraggMirror, methods=(1, 2, 3, 4), s: int = 3, wavelength_step: float = 1.0,
                    cos_theta=None, reference: np.ndarray | None = None) -> dict[int, MethodAccuracy]:
    """
    ΔE2000 (median, max over θ) of ``methods`` against ``reference`` (default: the converged table read at
    ``cos_theta``, default the gradient's :data:`BADGE_WIDTH` columns).
    """
    cos_theta = gradient_cos_theta() if cos_theta is None else np.asarray(cos_theta, dtype=np.float64)
    table = bragg.tabulated_rgb_table(mirror) if (reference is None or 3 in methods) else None
    if reference is None:
        reference = bragg.tabulated_rgb(table, cos_theta)
    result = {}
    for method in methods:
        rgb = method_rgb(mirror, method, cos_theta, s, wavelength_step, table)
        dE = colorimetry.delta_E_2000(reference, rgb)
        result[method] = MethodAccuracy(method, float(np.median(dE)), float(np.max(dE)))
    return result


def accuracy_badge(material, values: Mapping[str, object]) -> AccuracyBadge | None:
    """
    The badge of ``material`` at ``values`` (None unless its model is a Bragg mirror's with a ``method``):
    the current method (method 0 at its ``wavelength_step``: the paper's 1-nm sum is not converged for N
    of a few tens and more) and, when it is off, every closed-form method and the tabulated one.
    """
    from explorer.materials.twins import capabilities_of

    capabilities = capabilities_of(material)
    # A material whose ``method`` picks one of the RGB methods of a smooth Bragg mirror (its ``reflectance``).
    if not (capabilities.bragg_spectrum and capabilities.methods is BraggMethod) or "method" not in values:
        return None
    from explorer.materials.models import model_for

    model = model_for(material, values)
    if model.method not in METHOD_NAMES:
        return None
    if getattr(model, "natural", None) is not None:  # the exact table whatever the method
        exact = MethodAccuracy(model.method, 0.0, 0.0)
        return AccuracyBadge(model.method, {model.method: exact}, natural=True)
    options = dict(s=model.s, wavelength_step=model.wavelength_step)
    accuracies = mirror_accuracy(model.mirror, (model.method,), **options)
    if not accuracies[model.method].accurate:  # only then are the others needed (render's note, the app's hint)
        others = tuple(int(m) for m in BraggMethod if m is not BraggMethod.REFERENCE and m != model.method)
        accuracies.update(mirror_accuracy(model.mirror, others, **options))
    return AccuracyBadge(model.method, accuracies)
