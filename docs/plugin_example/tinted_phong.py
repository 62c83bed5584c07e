"""
The numpy twin of tinted_phong.brd, beside it: the same model in float64 (docs/plugins.md).

``bragg-explorer check tinted_phong.brd`` renders both, view by view, and compares them.
"""

import numpy as np

from explorer.plugins import Capabilities, twin


@twin
class TintedPhong:
    """Schlick's Fresnel of colour ``F0`` on a normalised Blinn-Phong lobe of ``exponent``."""

    name = "tinted_phong"  # the material file's '# model:' line
    capabilities = Capabilities(
        methods=None,  # no 'int method' parameter
        dirac=False,  # a lobe, not a smooth mirror's Dirac
        bragg_spectrum=False,  # its values do not describe a Bragg mirror
        numpy=True,  # render --engine numpy draws this class
        albedo=("numpy", "gl"),  # albedo --engine numpy and gl
        exports=("brdf", "table"),  # export --to brdf and --to table
        design=None,  # no inverse design (a DesignModel(...) declares its parameters and forward model)
    )

    def __init__(self, values):
        self.F0 = np.asarray(values["F0"], dtype=np.float64)
        self.exponent = float(values["exponent"])

    def reflectance(self, cos_theta):
        """The shader's ``reflectance(cos_theta)``: ``(..., 3)`` linear RGB."""
        m = np.clip(1.0 - np.asarray(cos_theta, dtype=np.float64), 0.0, 1.0)[..., None]
        return self.F0 + (1.0 - self.F0) * m**5

    def brdf(self, L, V, N, X, Y):
        """The shader's ``BRDF(L, V, N, X, Y)`` for unit vectors ``(..., 3)``."""
        H = np.asarray(L, dtype=np.float64) + np.asarray(V, dtype=np.float64)
        H = H / np.linalg.norm(H, axis=-1, keepdims=True)
        cos_h = np.maximum(np.sum(np.asarray(N) * H, axis=-1), 0.0)
        lobe = (self.exponent + 2.0) / (8.0 * np.pi) * cos_h**self.exponent
        return self.reflectance(np.clip(np.sum(H * L, axis=-1), 0.0, 1.0)) * lobe[..., None]

    def textures(self):
        """The tables the shader samples: none."""
        return {}
