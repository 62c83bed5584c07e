"""
BRDF Explorer's plots as views (``shaders/views/{theta_v,theta_h,theta_d,lobe3d,albedo}.glsl``), in numpy:
what each sample of a plot evaluates, the settings they take, and what a plot shows of the values.

Every plot is an image like the other views, so that the GL renderer draws it and the numpy twin
(:func:`explorer.views.render.render_numpy`) mirrors it pixel by pixel:

- ``theta_v``: column ``i`` at ``theta_v = -90 + 180 (i + 1/2) / W`` degrees, ``V = (sin theta_v cos phi_v,
  sin theta_v sin phi_v, cos theta_v)`` (a negative ``theta_v`` lies at ``phi_v + 180``), the light ``L`` at
  ``--light``: the material's BRDF across the plane of azimuth ``phi_v`` (BRDF Explorer's "theta V" plot);
- ``theta_h``: column ``i`` at ``theta_h = 90 (i + 1/2) / W``, at a fixed ``theta_d`` (``phi_h = 0``,
  ``phi_d = 90``: the slice view's Rusinkiewicz construction, :func:`explorer.views.geometry.brdf_view_geometry`);
- ``theta_d``: column ``i`` at ``theta_d = 90 (i + 1/2) / W``, at a fixed ``theta_h``;
- ``lobe3d``: the BRDF over the outgoing hemisphere for the light at ``--light``, column ``i`` at
  ``phi_o = 360 (i + 1/2) / W``, row ``j`` (from the top) at ``theta_o = 90 (j + 1/2) / H``: the radius of
  BRDF Explorer's 3D lobe in every direction;
- ``albedo``: column ``i`` at ``theta_i = 90 (i + 1/2) / W``: the directional albedo (BRDF x cos integrated
  over the outgoing hemisphere, plus a Dirac's weight), on the half-vector quadrature of
  :func:`explorer.views.albedo.half_vector_quadrature`, which the shader evaluates on the same nodes.

The curves' rows are all the same (a height of 1 is enough). Every sample is the BRDF under the views'
rule (:func:`explorer.views.geometry.view_brdf`), linear RGB. What is plotted of it (:func:`plotted`):
times ``N.L`` (``--ndotl``), one channel or the luminance (``--channel``), ``log10(1 + x)`` (``--log``).
Angles are computed in float32 as the shaders compute them; the BRDF in float64.

References
----------
Burley (2012), Physically-Based Shading at Disney (BRDF Explorer's plots); Rusinkiewicz (1998), A New
Change of Variables for Efficient BRDF Representation (theta_h, theta_d, phi_d).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: The curves' views (one value per column) and the 3D lobe (one value per direction).
CURVE_VIEWS = ("theta_v", "theta_h", "theta_d", "albedo")
#: The length of the albedo shader's node arrays (``ALBEDO_MAX_NODES`` in ``shaders/views/albedo.glsl``).
ALBEDO_MAX_NODES = 256
#: ``--channel`` choices; ``rgb`` plots the three.
CHANNELS = ("rgb", "r", "g", "b", "luminance")
#: The abscissa of each curve: (label, first, last) in degrees; samples at cell centres between them.
ABSCISSAE = {
    "theta_v": ("theta_v (deg)", -90.0, 90.0),
    "theta_h": ("theta_h (deg)", 0.0, 90.0),
    "theta_d": ("theta_d (deg)", 0.0, 90.0),
    "albedo": ("theta_i (deg)", 0.0, 90.0),
}
#: Which settings each plot takes (``--theta-d``, ``--theta-h``, ``--phi-v``).
PLOT_SETTINGS = {"theta_v": ("phi_v",), "theta_h": ("theta_d",), "theta_d": ("theta_h",), "lobe3d": (), "albedo": ()}


@dataclass(frozen=True)
class PlotSettings:
    """
    A plot's sliders (degrees) and what it shows: ``theta_d`` (the ``theta_h`` plot), ``theta_h`` (the
    ``theta_d`` plot), ``phi_v`` (the ``theta_v`` plot); ``log`` (``log10(1 + x)``), ``channel``
    (:data:`CHANNELS`), ``ndotl`` (times ``N.L``).
    """

    theta_d: float = 0.0
    theta_h: float = 0.0
    phi_v: float = 0.0
    log: bool = False
    channel: str = "rgb"
    ndotl: bool = False

    def __post_init__(self):
        for name in ("theta_d", "theta_h"):
            value = getattr(self, name)
            if not (np.isfinite(value) and 0.0 <= value <= 90.0):
                raise ValueError(f"--{name.replace('_', '-')} {value:g}: must be in [0, 90] degrees")
        if not np.isfinite(self.phi_v):
            raise ValueError(f"--phi-v {self.phi_v}: must be finite")
        if self.channel not in CHANNELS:
            raise ValueError(f"--channel {self.channel!r}: one of {', '.join(CHANNELS)}")

    def gl_uniforms(self) -> dict[str, float]:
        """The plot views' uniforms (radians), as ``shaders/views/*.glsl`` declare them."""
        return {"plot_theta_d": float(np.radians(self.theta_d)), "plot_theta_h": float(np.radians(self.theta_h)),
                "plot_phi_v": float(np.radians(self.phi_v))}


def abscissa(view: str, width: int) -> np.ndarray:
    """The curve's sample angles (degrees, float64) of a ``width``-sample curve."""
    _, first, last = ABSCISSAE[view]
    return first + (last - first) * (np.arange(width) + 0.5) / width


def _unit(theta, phi) -> np.ndarray:
    """``(sin theta cos phi, sin theta sin phi, cos theta)`` in float32, ``(..., 3)``."""
    theta, phi = np.broadcast_arrays(theta, phi)
    return np.stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)], axis=-1)


def _column_angle(width: int, first: float, last: float) -> np.ndarray:
    """Column ``i``'s angle in radians, in float32 as the shaders' ``plot_column_angle``."""
    f32 = np.float32
    fx = np.arange(width, dtype=f32) + f32(0.5)
    return f32(np.radians(first)) + f32(np.radians(last - first)) * fx / f32(width)


def rusinkiewicz_directions(theta_h, theta_d, phi_d: float = np.pi / 2) -> tuple[np.ndarray, np.ndarray]:
    """
    ``(L, V)`` of half-vector angle ``theta_h`` (``phi_h = 0``) and difference angles ``theta_d``, ``phi_d``
    (Rusinkiewicz 1998), float32 ``(..., 3)``: the twin of ``rusinkiewicz_directions`` in ``shaders/lib/views.glsl``,
    the slice view's construction (``D`` rotated by ``theta_h`` about ``Y``; ``V`` the reflection of ``L`` about ``H``).
    """
    f32 = np.float32
    theta_h, theta_d = np.asarray(theta_h, f32), np.asarray(theta_d, f32)
    theta_h, theta_d = np.broadcast_arrays(theta_h, theta_d)
    H = _unit(theta_h, np.zeros_like(theta_h))
    D = _unit(theta_d, np.full_like(theta_d, f32(phi_d)))
    # Rotation by theta_h about Y = (0, 1, 0): (x, y, z) -> (x cos + z sin, y, -x sin + z cos).
    c, s = np.cos(theta_h), np.sin(theta_h)
    L = np.stack([D[..., 0] * c + D[..., 2] * s, D[..., 1], -D[..., 0] * s + D[..., 2] * c], axis=-1)
    V = f32(2.0) * np.sum(H * L, axis=-1, keepdims=True) * H - L
    return L.astype(f32), V.astype(f32)


def plot_geometry(view: str, width: int, height: int, light_direction: np.ndarray, settings: PlotSettings):
    """
    ``(L, V)`` at each pixel of a BRDF plot view (``theta_v``, ``theta_h``, ``theta_d``, ``lobe3d``), float32
    ``(height, width, 3)``, computed as its shader does; ``N``, ``X``, ``Y`` are the z, x and y axes.
    """
    f32 = np.float32
    shape = (height, width, 3)
    L = np.broadcast_to(np.asarray(light_direction, f32), shape)
    if view == "theta_v":
        theta_v = _column_angle(width, -90.0, 90.0)
        V = _unit(theta_v, np.full_like(theta_v, f32(np.radians(settings.phi_v))))
        return L, np.broadcast_to(V[None, :, :], shape)
    if view in ("theta_h", "theta_d"):
        angle = _column_angle(width, 0.0, 90.0)
        if view == "theta_h":
            Lc, Vc = rusinkiewicz_directions(angle, np.full_like(angle, f32(np.radians(settings.theta_d))))
        else:
            Lc, Vc = rusinkiewicz_directions(np.full_like(angle, f32(np.radians(settings.theta_h))), angle)
        return np.broadcast_to(Lc[None], shape), np.broadcast_to(Vc[None], shape)
    if view == "lobe3d":
        phi_o = _column_angle(width, 0.0, 360.0)
        fy = np.arange(height, dtype=f32) + f32(0.5)  # rows from the top
        theta_o = f32(np.radians(90.0)) * fy / f32(height)
        V = _unit(theta_o[:, None], phi_o[None, :])
        return L, V
    raise ValueError(f"{view!r} is not a BRDF plot view")


def lobe_directions(width: int, height: int) -> tuple[np.ndarray, np.ndarray]:
    """The lobe3d view's ``(theta_o, phi_o)`` per pixel in radians, float64 ``(height, width)``."""
    theta_o = np.radians(90.0) * (np.arange(height) + 0.5) / height
    phi_o = np.radians(360.0) * (np.arange(width) + 0.5) / width
    return np.broadcast_to(theta_o[:, None], (height, width)), np.broadcast_to(phi_o[None, :], (height, width))


def plot_numpy(model, view: str, width: int, height: int, light_direction: np.ndarray, settings: PlotSettings) -> np.ndarray:
    """The numpy twin of a plot view: ``(height, width, 3)`` float32 linear RGB (see the module's docstring)."""
    from explorer.views.geometry import view_brdf

    if view == "albedo":
        from explorer.views.albedo import albedo_numpy

        theta = abscissa("albedo", width)
        curve = albedo_numpy(model, theta)
        return np.broadcast_to(curve[None].astype(np.float32), (height, width, 3)).copy()
    if not callable(getattr(model, "brdf", None)):
        raise ValueError(f"the {view} view needs the model's brdf(L, V, N, X, Y); {type(model).__name__} has none")
    L, V = plot_geometry(view, width, height, light_direction, settings)
    frame = [np.broadcast_to(np.array(a, np.float32), (height, width, 3)) for a in ([0, 0, 1], [1, 0, 0], [0, 1, 0])]
    if view == "lobe3d":
        return view_brdf(model.brdf, L, V, *frame).astype(np.float32)
    row = view_brdf(model.brdf, L[:1], V[:1], *(a[:1] for a in frame))  # every row is the same
    return np.broadcast_to(row, (height, width, 3)).astype(np.float32)


def cos_light(view: str, width: int, height: int, light_direction: np.ndarray, settings: PlotSettings) -> np.ndarray:
    """``N.L`` per sample of a plot (``--ndotl``): the light's cosine, or the incidence angle's (albedo), ``(height, width)``."""
    if view == "albedo":
        return np.broadcast_to(np.cos(np.radians(abscissa("albedo", width)))[None], (height, width))
    L, _ = plot_geometry(view, width, height, light_direction, settings)
    return np.maximum(L[..., 2].astype(np.float64), 0.0)


def plotted(values: np.ndarray, settings: PlotSettings, cos_l: np.ndarray | None = None) -> np.ndarray:
    """
    What a plot shows of its ``(..., 3)`` linear RGB ``values``: times ``cos_l`` (``--ndotl``), the channel
    (``(..., 3)`` for ``rgb``, ``(..., 1)`` otherwise; ``luminance`` is CIE Y of the linear sRGB, the
    project's colour convention), ``log10(1 + x)`` (``--log``; negative values, out of gamut, clipped at 0 there).
    """
    from explorer.physics.colorimetry import rgb_to_xyz

    values = np.asarray(values, dtype=np.float64)
    if settings.ndotl:
        values = values * np.asarray(cos_l, dtype=np.float64)[..., None]
    if settings.channel == "luminance":
        values = rgb_to_xyz(values)[..., 1:2]
    elif settings.channel != "rgb":
        k = "rgb".index(settings.channel)
        values = values[..., k:k + 1]
    if settings.log:
        values = np.log10(1.0 + np.maximum(values, 0.0))
    return values


def albedo_uniforms() -> dict[str, object]:
    """The albedo view's quadrature (``shaders/views/albedo.glsl``): :func:`explorer.views.albedo.theta_h_nodes` and the azimuths."""
    from explorer.views.albedo import PHI_H_NODES, theta_h_nodes

    theta_h, d_theta = theta_h_nodes()
    padded = [np.zeros(ALBEDO_MAX_NODES) for _ in range(2)]  # the shader's arrays are ALBEDO_MAX_NODES long
    padded[0][:theta_h.size], padded[1][:theta_h.size] = theta_h, d_theta
    return {"albedo_nodes": int(theta_h.size), "albedo_theta_h": tuple(float(t) for t in padded[0]),
            "albedo_d_theta": tuple(float(w) for w in padded[1]), "albedo_phi_nodes": int(PHI_H_NODES)}


def gl_uniforms(view: str, settings: PlotSettings | None) -> dict[str, object]:
    """The uniforms a plot view's shader needs besides the material's and the light."""
    uniforms = (settings or PlotSettings()).gl_uniforms()
    if view == "albedo":
        uniforms.update(albedo_uniforms())
    return uniforms
