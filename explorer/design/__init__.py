"""
Inverse design of Bragg mirrors and thin films: from the colours wanted at a few angles to the structure
that makes them, or the structure that comes closest when none does.

The forward model is the converged spectral colour of the smooth structure at each target angle (what the
tabulated method shows, :func:`explorer.physics.bragg.reference_rgb`,
:func:`explorer.physics.thinfilm.reference_rgb`). The search minimises the sum of the squared CIEDE2000
differences over the targets, in three stages:

1. a space-filling first pass: a scrambled Sobol sequence of shapes over the free parameters' box (``N`` on
   a log scale, continuous), each at every value of the length that scales it (:meth:`_Problem.scale_scan`:
   one spectrum per shape over ``s / lambda``, a correlation with the CMFs gives every scale); without a
   free scale, every candidate evaluated at once by the material's vectorised coarse model (its
   :attr:`DesignModel.batch`, e.g. over :func:`explorer.physics.bragg.bragg_reflectance_batch`: point samples
   every :data:`COARSE_STEP` nm);
   the best distinct shapes then walk downhill by the same scan, windowed around their period
   (:func:`_scan_descent`: a (1 + lambda) evolution whose moves shrink from 0.08 to 0.01 of the box);
2. local refinement (``scipy.optimize.least_squares``) of the best distinct candidates on the coarse model,
   with Jacobians by finite differences evaluated in one batch;
3. a polish of the best few on the converged model with ``N`` rounded to an integer.

With ``tries`` above 1, a design that leaves a target above :data:`REACHED_DELTA_E` searches again from a
fresh first pass with the best structure so far among its guesses (an iterated search with restarts).

Residuals are the CIELAB differences scaled per target by ``dE2000 / dE76``, so that their squared norm per
target is exactly CIEDE2000 squared while staying differentiable.

References
----------
Fourneau, Pacanowski, Barla (2024). Interactive Exploration of Vivid Material Iridescence using Bragg
Mirrors. CGF 43(2): Eqs. 2, 8-10 (Yeh's reflectance), Appendix D (the host), Section 7 (inverse design
named as future work).
Belcour & Barla (2017). A Practical Extension to Microfacet Theory for the Modeling of Varying
Iridescence. ACM TOG 36(4): Eqs. 2-3 (the film's Airy reflectance).
Sharma, Wu, Dalal (2005). The CIEDE2000 colour-difference formula. Color Res. Appl. 30(1).

The package by subject (every public name is re-exported here, so ``design.NAME`` reads the same):

- :mod:`~explorer.design.base`: the search's settings, its errors, a design parameter and a design model;
- :mod:`~explorer.design.forward`: the designable models, asked of the registry (each twin declares its forward
  model, :class:`explorer.materials.twins.DesignModel`);
- :mod:`~explorer.design.targets`: target colours (checked, or read from a strip), the result and the parameter box;
- :mod:`~explorer.design.search`: the problem and the search's stages (scans, descent, refinement, polish);
- :mod:`~explorer.design.solve`: :func:`design`, with tries;
- :mod:`~explorer.design.studies`: what the studies ask of it (forward colours, reachable colours, the round trip).

Colours are compared in CIELAB with CIEDE2000 (:func:`explorer.physics.colorimetry.rgb_to_lab`,
:func:`explorer.physics.colorimetry.delta_E_2000_lab`).
"""

# Each subject declares its public names (its __all__); the package only re-exports them. The search's stages are
# private to explorer.design.search (a test or a study imports them from there).
from explorer.design.base import *  # noqa: F401,F403
from explorer.design.forward import *  # noqa: F401,F403
from explorer.design.solve import *  # noqa: F401,F403
from explorer.design.studies import *  # noqa: F401,F403
from explorer.design.targets import *  # noqa: F401,F403
