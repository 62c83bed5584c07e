"""
The numpy twin of ``shaders/thin_film.brd`` (Belcour & Barla 2017; physics in :mod:`explorer.physics.thinfilm`).

The material is a GGX microfacet BRDF whose Fresnel term is a thin film's Airy reflectance at the
half-vector angle; ``method`` picks how that reflectance becomes a colour:

(:class:`explorer.materials.methods.ThinFilmMethod`): the spectral reference (the Airy reflectance at
every nm from 360 to 830, both polarisations); the paper's Fourier-space spectral integration (Eq. 10)
summed to m = 1, 2, 3 with the tabulated transform of the convention's sensitivities
(``luts/sensitivity_fourier.npy``) and the series' remainder; the same at m = 3 with the paper's Gaussian
fits of the XYZ sensitivities; naive RGB (the Airy reflectance at
:data:`explorer.physics.thinfilm.NAIVE_WAVELENGTHS`).
"""

from __future__ import annotations

from typing import Mapping

import numpy as np

from explorer.physics import colorimetry, microfacet, thinfilm
from explorer.materials.twins import Capabilities, DesignModel, StructureMaps, twin
from explorer.materials.brd import round_integer
from explorer.materials.methods import ThinFilmMethod

#: The methods that integrate with the tabulated sensitivities (and may be prefiltered).
TABULATED_FOURIER = (ThinFilmMethod.FOURIER_1, ThinFilmMethod.FOURIER_2, ThinFilmMethod.FOURIER_3)


#: The film's colour per method (the shader's branches on THIN_FILM_* in thin_film.brd).
FILM_RGB = {
    ThinFilmMethod.REFERENCE: lambda film, c, d: thinfilm.reference_rgb(*film, c, d, step=1.0),  # the shader's 1-nm sum
    **{m: (lambda film, c, d, m=m: thinfilm.fourier_rgb(*film, c, d, m_max=m.m_max, sensitivity="table"))
       for m in TABULATED_FOURIER},
    ThinFilmMethod.GAUSSIAN: lambda film, c, d: thinfilm.fourier_rgb(
        *film, c, d, m_max=ThinFilmMethod.GAUSSIAN.m_max, sensitivity="gaussian"),
    ThinFilmMethod.NAIVE: lambda film, c, d: thinfilm.naive_rgb(*film, c, d),
}


def film_rgb(method: ThinFilmMethod, film, cos_theta, d) -> np.ndarray:
    """The film's colour by ``method`` (:data:`FILM_RGB`)."""
    return FILM_RGB[method](film, cos_theta, d)


# --------------------------------------------------------------------------------------------------
# Inverse design's forward model of a film


def thin_film_rgb_batch(values: Mapping[str, np.ndarray], cos_theta, step: float = colorimetry.COARSE_STEP,
                        smooth: float | None = None) -> np.ndarray:
    """
    The coarse colours ``(B, A, 3)`` of films ``values`` (``d``, ``eta1``, ``eta2``, ``eta3``, ``kappa3``); a
    film's few fringes are its colour, so ``smooth`` is not used.
    """
    nodes, weights = colorimetry.interpolant_nodes(step)
    return colorimetry.xyz_to_rgb(thin_film_spectra_batch(values, cos_theta, nodes) @ weights)


def thin_film_spectra_batch(values: Mapping[str, np.ndarray], cos_theta, wavelengths, smooth_relative: float = 0.0) -> np.ndarray:
    """The films' Airy spectra ``(B, A, W)`` (not smoothed: a film's fringes are its colour)."""
    col = lambda name: np.asarray(values[name], dtype=np.float64).reshape(-1, 1, 1)
    cos = np.asarray(cos_theta, dtype=np.float64).reshape(1, -1, 1)
    return thinfilm.airy_reflectance(col("eta1"), col("eta2"), col("eta3"), col("kappa3"), cos, col("d"),
                                     np.asarray(wavelengths, float))


def thin_film_converged_rgb(values: Mapping[str, float], cos_theta, final: bool = True) -> np.ndarray:
    """The film's converged colours (:func:`explorer.physics.thinfilm.reference_rgb`)."""
    return thinfilm.reference_rgb(float(values["eta1"]), float(values["eta2"]), float(values["eta3"]),
                                  float(values["kappa3"]), np.asarray(cos_theta, dtype=np.float64), float(values["d"]))


#: What design fits of a film, on its Airy reflectance: the thickness scanned, the indices and absorption.
THIN_FILM_DESIGN = DesignModel(parameters=("d", "eta1", "eta2", "eta3", "kappa3"), batch=thin_film_rgb_batch,
                               converged=thin_film_converged_rgb, scale_parameter="d", spectra=thin_film_spectra_batch,
                               paint_free=("d",))


#: Structure maps on a film: each texel its own film (the shader's ``textured_reflectance`` under ``TEXTURE_MAPS``).
THIN_FILM_MAPS = StructureMaps(fields=("d", "eta1", "eta2", "eta3", "kappa3"))


@twin
class ThinFilmModel:
    """Twin of ``shaders/thin_film.brd``: ``reflectance(cos_theta)`` and ``brdf(L, V, N, X, Y)``, every method."""

    name = "thin_film"
    capabilities = Capabilities(methods=ThinFilmMethod, dirac=False, bragg_spectrum=False, numpy=True,
                                albedo=("numpy", "gl"), exports=("mitsuba", "brdf", "table", "materialx", "gltf"),
                                design=THIN_FILM_DESIGN, maps=THIN_FILM_MAPS)

    def __init__(self, values: Mapping[str, object]):
        self.values = dict(values)
        self.thickness_d = float(values["d"])
        self.eta_1 = float(values["eta1"])
        self.eta_2 = float(values["eta2"])
        self.eta_3 = float(values["eta3"])
        self.kappa_3 = float(values["kappa3"])
        self.alpha = float(values.get("alpha", 0.0))
        method = round_integer(values.get("method", 0))
        if method not in set(ThinFilmMethod):
            raise ValueError(f"method must be one of {', '.join(str(int(m)) for m in ThinFilmMethod)}, got {method}")
        self.method = ThinFilmMethod(method)
        # One-line ValueErrors on a negative thickness, kappa3 < 0, non-positive or non-finite indices.
        thinfilm.validate_film(self.eta_1, self.eta_2, self.eta_3, self.kappa_3, 1.0, self.thickness_d)
        microfacet.check_alpha(self.alpha)

    @property
    def film(self) -> tuple[float, float, float, float]:
        """``(eta_1, eta_2, eta_3, kappa_3)``."""
        return self.eta_1, self.eta_2, self.eta_3, self.kappa_3

    def reflectance(self, cos_theta) -> np.ndarray:
        """The smooth film's linear RGB reflectance at incidence ``cos_theta`` (shape ``(..., 3)``)."""
        return film_rgb(self.method, self.film, np.asarray(cos_theta, dtype=np.float64), self.thickness_d)

    def textured_reflectance(self, cos_theta, D_inc, sigma_D_inc, prefiltered: bool, mapping: str | None = None,
                             structures: np.ndarray | None = None) -> np.ndarray:
        """
        The twin of the shader's ``textured_reflectance``: the film of OPD ``D_inc`` (nm, per sample) at
        normal incidence (:func:`explorer.physics.thinfilm.film_from_D_inc`) instead of ``d``; with ``prefiltered``
        (methods 1-3), Eq. 10 averaged over a Gaussian of ``D_inc`` of standard deviation ``sigma_D_inc``
        (:func:`explorer.physics.thinfilm.fourier_rgb_prefiltered`, Section 5). ``mapping="maps"``: ``D_inc`` is a
        texel index of ``structures`` (:data:`THIN_FILM_MAPS`' table), each texel its own film, 0 off the maps' mask.
        """
        cos_theta = np.asarray(cos_theta, dtype=np.float64)
        if mapping == "maps":
            return self._mapped_reflectance(cos_theta, np.broadcast_to(np.asarray(D_inc, np.float64), cos_theta.shape), structures)
        eta_2, d = thinfilm.film_from_D_inc(D_inc, self.eta_1, self.eta_2)
        film = (self.eta_1, eta_2, self.eta_3, self.kappa_3)
        if prefiltered:
            if self.method not in TABULATED_FOURIER:
                names = ", ".join(f"{int(m)} ({m.label})" for m in TABULATED_FOURIER)
                raise ValueError(f"prefiltering needs a tabulated Fourier method ({names}), not method {int(self.method)}")
            return thinfilm.fourier_rgb_prefiltered(*film, cos_theta, d, sigma_D_inc, m_max=self.method.m_max)
        return film_rgb(self.method, film, cos_theta, d)

    def _mapped_reflectance(self, cos_theta: np.ndarray, index: np.ndarray, structures: np.ndarray) -> np.ndarray:
        """Each sample's texel film (float32 fields, as the shader reads them) by ``method``, grouped by its scalar indices."""
        from explorer.physics.structure_maps import structure_texels

        inside, slots = structure_texels(structures, index)
        rgb = np.zeros(cos_theta.shape + (3,))
        scalars = slots[..., [1, 3, 4]]  # eta1, eta3, kappa3 (d and eta2 go per sample)
        for key in np.unique(scalars[inside], axis=0):
            samples = inside & np.all(scalars == key, axis=-1)
            eta_1, eta_3, kappa_3 = (float(v) for v in key)
            rgb[samples] = film_rgb(self.method, (eta_1, slots[..., 2][samples], eta_3, kappa_3), cos_theta[samples], slots[..., 0][samples])
        return rgb

    def surface_reflectance(self, cos_theta, value, **options) -> np.ndarray:
        """The flat textured view's colour at ``cos_theta`` of surface values ``value`` (the shader's ``surface_reflectance``)."""
        return self.textured_reflectance(cos_theta, value, np.zeros(np.shape(value)), False, **options)

    def textured_brdf(self, L, V, N, X, Y, D_inc, sigma_D_inc, prefiltered: bool, mapping: str | None = None,
                      structures: np.ndarray | None = None) -> np.ndarray:
        """The shader's ``textured_BRDF``: :meth:`brdf` with :meth:`textured_reflectance` per sample."""
        D_inc, sigma_D_inc = np.asarray(D_inc, np.float64), np.asarray(sigma_D_inc, np.float64)
        return self._brdf(L, V, N, lambda cos_d, above: self.textured_reflectance(cos_d, D_inc[above], sigma_D_inc[above], prefiltered,
                                                                                  mapping, structures))

    def brdf(self, L, V, N, X, Y) -> np.ndarray:
        """The shader's ``BRDF`` (see :meth:`_brdf`) with the film's uniform thickness ``d``."""
        return self._brdf(L, V, N, lambda cos_d, above: self.reflectance(cos_d))

    def _brdf(self, L, V, N, reflectance) -> np.ndarray:
        """
        The shader's ``BRDF``: ``D(h) G1(L) G1(V) F(theta_d) / (4 cos theta_i cos theta_o)`` with GGX ``D``,
        Smith's ``G1`` and ``F`` the film's reflectance at ``cos theta_d = |L + V| / 2``; 0 where ``L`` or
        ``V`` is at or below the surface. Unit vectors of shape ``(..., 3)``; returns ``(..., 3)``.
        """
        lobe, cos_theta_d, above = microfacet.microfacet_lobe(L, V, N, self.alpha)
        result = np.zeros(lobe.shape + (3,))
        if above.any():
            result[above] = lobe[above, None] * reflectance(cos_theta_d[above], above)
        return result

    def spectral_brdf(self, i, o, wavelengths, rgb_upsample) -> np.ndarray:
        """The BRDF per wavelength for Mitsuba: the GGX lobe times the film's Airy reflectance at ``theta_d``."""
        lobe, cos_d, _ = microfacet.microfacet_lobe(i, o, np.array([0.0, 0.0, 1.0]), self.alpha)
        F = thinfilm.airy_reflectance(self.eta_1, self.eta_2, self.eta_3, self.kappa_3,
                                      np.clip(cos_d, microfacet.COS_THETA_MIN, 1.0)[:, None], self.thickness_d, wavelengths)
        return lobe[:, None] * F

    def sampling_lobes(self, cos_o):
        """``(alphas, weights, cosine_weight)`` at view cosines ``(n,)``: one GGX lobe (the shader's ``sampling_lobes``)."""
        ones = np.ones_like(cos_o)
        return [max(self.alpha, 1e-4)], [ones], 0.0 * ones

    def brdf_export(self) -> dict:
        """
        How ``export --to brdf`` specialises the film (:mod:`explorer.materials.export_brdf`): to its method, since
        the 4096 x 2 ``sensitivity_fourier`` table, inlined, takes Mesa's compiler many minutes; methods 1-3 read
        its envelope through a coarse copy instead (``coarse_envelope``), the others not at all.
        """
        return {"defines": {"SPECIALISED_method": str(int(self.method))}, "drop_tables": ("sensitivity_fourier",),
                "coarse_envelope": self.method in TABULATED_FOURIER}

    def textures(self) -> dict[str, np.ndarray]:
        """None of its own: the ``sensitivity_fourier`` table is a library texture (:mod:`explorer.gpu.renderer`)."""
        return {}
