"""
Thin films: the Airy reflectance of a dielectric film over a dielectric or conducting base, and its
analytic spectral integration in Fourier space (Belcour & Barla 2017).

A film of real index ``eta_2`` and thickness ``thickness_d`` (nm) lies on a base of complex index
``eta_3 + i kappa_3`` (``kappa_3 = 0``: a dielectric, ``kappa_3 > 0``: a conductor), under an
exterior medium of real index ``eta_1``. Light arrives from the exterior; ``cos_theta_1`` is the
cosine of its angle of incidence (the paper's ``h . omega_i``), kept at or above
:data:`COS_THETA_MIN` as in :mod:`explorer.physics.bragg`. Wavelengths and optical path differences are in
nm. Every function broadcasts its arguments against each other (angles, wavelengths and the
material's parameters alike).

Conventions are those of :mod:`explorer.physics.fresnel` and of ``tmm``: waves travel as ``exp(+i k_z z)``,
an absorbing index is ``eta + i kappa`` with ``kappa >= 0``, and ``r_p`` has ``tmm``'s sign. They are
also the paper's: its Eq. 3 has ``exp(+i Delta phi)`` and its base ``eta_3 + i kappa_3``, so the
phases on reflection ``phi_ab = arg(r_ab)`` are used exactly as its Eqs. 5-10 write them.

Colours follow the product's convention (:mod:`explorer.physics.colorimetry`) and come out in linear sRGB,
unclamped:

- :func:`reference_rgb`, the spectral reference: the exact Airy reflectance at every nm from 360 to
  830, both polarisations, integrated against the CMFs;
- :func:`fourier_rgb`, the paper's method: Eq. 10 truncated at ``m_max`` (1 to 3), with the Fourier
  transform of this convention's RGB sensitivities tabulated in ``luts/`` (``'table'``), the paper's
  Gaussian fits (``'gaussian'``), or computed exactly (``'exact'``, for validation);
- :func:`naive_rgb`: the Airy reflectance at one wavelength per channel (:data:`NAIVE_WAVELENGTHS`).

The Appendix's closed form of ``R`` cancels catastrophically near grazing incidence; it is evaluated
here in the exactly equivalent form ``R = 1 - T12 T23 / |1 - R_l e^{i Phi}|^2`` (see
:func:`airy_reflectance_from_terms`), and ``C_m`` likewise (:func:`C_m`).

References
----------
Belcour, Barla (2017). A Practical Extension to Microfacet Theory for the Modeling of Varying
Iridescence. ACM Transactions on Graphics 36(4), Article 65. Sections 3-5 and Appendix.
Born and Wolf, Principles of Optics, Sections 1.5-1.6 and 13.2. Yeh (1988), Optical Waves in Layered
Media, Section 4.2 (Airy summation).

The subpackage by subject (every name is re-exported here, so ``thinfilm.NAME`` reads the same):

- :mod:`~explorer.physics.thinfilm.airy`: the film at one angle and polarisation, Snell and Fresnel with a conducting
  base, the Airy reflectance and transmittance, and the Fourier series of R (Eqs. 2-6, Appendix);
- :mod:`~explorer.physics.thinfilm.fourier`: the sensitivities in Fourier space, the analytic spectral integration
  (Eq. 10), the colours (spectral reference, Fourier and naive methods), the ``D_inc`` parametrisation and the
  multi-scale (pre-filtered) rendering (Section 5).
"""

from explorer.physics.thinfilm.airy import (  # noqa: F401
    C_0,
    COS_THETA_MIN,
    POLARISATIONS,
    C_m,
    FilmTerms,
    _airy_denominator,
    _airy_series_factor,
    _complex_phase,
    _Phi,
    _polarisation_average,
    _polarisations,
    _power_factor,
    _real_array,
    _validate_wavelength,
    airy_reflectance,
    airy_reflectance_appendix_from_terms,
    airy_reflectance_from_terms,
    airy_reflection_coefficient,
    airy_reflection_coefficient_from_terms,
    airy_transmission_coefficient_from_terms,
    airy_transmittance,
    airy_transmittance_from_terms,
    cos_theta_transmitted_conductor,
    film_terms,
    fresnel_t,
    optical_path_difference,
    phase_shift,
    validate_film,
)
from explorer.physics.thinfilm.fourier import (  # noqa: F401
    _PREFILTERED,
    D_INC_BLEND,
    GAUSSIAN_FIT_NORM,
    GAUSSIAN_FIT_POS,
    GAUSSIAN_FIT_VAL,
    GAUSSIAN_FIT_VAR,
    GAUSSIAN_FIT_X2,
    NAIVE_WAVELENGTHS,
    PAPER_XYZ_WAVELENGTHS,
    PREFILTER_LEVELS,
    PREFILTER_SIGMA_STEP,
    REMAINDER_MIN,
    SENSITIVITIES,
    SENSITIVITY_FOURIER_CARRIER_NM,
    SENSITIVITY_FOURIER_COUNT,
    SENSITIVITY_FOURIER_STEP,
    D_inc,
    D_max,
    _generate_sensitivity_fourier,
    _sensitivity_fourier_prefiltered,
    _with_axis,
    film_from_D_inc,
    fourier_remainder,
    fourier_rgb,
    fourier_rgb_prefiltered,
    naive_rgb,
    reference_rgb,
    sensitivities_rgb,
    sensitivity_fourier_prefiltered,
    sensitivity_fourier_transform,
    sensitivity_fourier_transform_exact,
    sensitivity_fourier_transform_gaussian_xyz,
    sensitivity_fourier_transform_prefiltered,
    sensitivity_fourier_transform_table,
    spectral_integration_fourier,
)
