"""
The views' geometry, in numpy (no GL): what each pixel of ``shaders/views/*.glsl`` shows, the views'
names, sizes and default light, and the rule every view evaluates a BRDF under. The numpy renders
(:mod:`explorer.views.render`), the environment view's twin (:mod:`explorer.views.env`), the GL host and the app
share it.

Pixel positions are computed in float32, as the fragment shader computes them, so that both sides
evaluate the material at the same angle; the physics then runs in float64.

``gradient`` and ``sphere`` show a material's ``reflectance(cos_theta)``; ``lit``, ``slice`` and
``scatter`` call its ``BRDF(L, V, N, X, Y)`` under one rule (:func:`view_brdf`,
``shaders/lib/views.glsl``): 0 unless ``N.L > 0`` and ``N.V > 0``, a NaN or infinite channel 0.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

@dataclass(frozen=True)
class View:
    """
    What one view is (its template is ``shaders/views/NAME.glsl``, its numpy twin
    :func:`explorer.views.render.render_numpy`): what it evaluates of a material (``reflectance``,
    ``brdf``, ``textured_brdf`` or ``environment``), its default size, whether ``--size W`` means a
    square, and the largest polar angle of its light (``None``: it takes no light).
    """

    name: str
    evaluates: str
    default_size: tuple[int, int] = (256, 256)
    square: bool = True
    light_theta_max: float | None = None
    #: Circles of constant theta_o drawn on PNG output (the paper's Figure 9).
    circles: bool = False
    #: A plot (:mod:`explorer.views.plots`): ``curve`` (one value per column, every row the same) or
    #: ``lobe`` (a value per outgoing direction); its PNG is a chart, its ``.npy`` the plotted values.
    plot: str | None = None
    #: Reads the surface texture of a material that declares ``# texture:`` (the host #defines SURFACE_TEXTURE).
    surface_texture: bool = False
    #: Its shader draws one term a fragment (one BRDF call) that the host sums per column
    #: (:meth:`explorer.gpu.Renderer.render`): a sum inside one fragment would outrun llvmpipe's loop limit.
    summed: bool = False

    @property
    def takes_light(self) -> bool:
        return self.light_theta_max is not None


#: Every view, in the order the CLI lists them.
VIEW_REGISTRY: dict[str, View] = {view.name: view for view in (
    View("gradient", "reflectance", default_size=(256, 32), square=False),
    View("sphere", "reflectance"),
    View("lit", "brdf", light_theta_max=180.0),
    View("slice", "brdf"),
    View("scatter", "brdf", light_theta_max=90.0, circles=True),
    View("textured", "textured_brdf", light_theta_max=180.0, surface_texture=True),
    View("env", "environment", surface_texture=True),
    # BRDF Explorer's plots (explorer/views/plots.py): curves W samples wide, the lobe over (phi_o, theta_o).
    View("theta_v", "brdf_plot", default_size=(512, 1), square=False, light_theta_max=90.0, plot="curve"),
    View("theta_h", "brdf_plot", default_size=(512, 1), square=False, plot="curve"),
    View("theta_d", "brdf_plot", default_size=(512, 1), square=False, plot="curve"),
    View("lobe3d", "brdf_plot", default_size=(128, 32), square=False, light_theta_max=90.0, plot="lobe"),
    View("albedo", "albedo", default_size=(90, 1), square=False, plot="curve", summed=True),
)}
VIEWS = tuple(VIEW_REGISTRY)
DEFAULT_SIZES = {name: view.default_size for name, view in VIEW_REGISTRY.items()}
#: Views that evaluate the material's BRDF(L, V, N, X, Y); those that take a light direction.
BRDF_VIEWS = tuple(name for name, view in VIEW_REGISTRY.items() if view.evaluates == "brdf")
LIGHT_VIEWS = tuple(name for name, view in VIEW_REGISTRY.items() if view.takes_light)
#: BRDF Explorer's plots (:mod:`explorer.views.plots`).
PLOT_VIEWS = tuple(name for name, view in VIEW_REGISTRY.items() if view.plot is not None)


def view_named(name: str) -> View:
    """The registered view ``name``; a one-line ``ValueError`` listing the views otherwise."""
    try:
        return VIEW_REGISTRY[name]
    except KeyError:
        from explorer.errors import did_you_mean

        raise ValueError(f"unknown view {name!r}{did_you_mean(name, VIEWS)} (views: {', '.join(VIEWS)})") from None


#: (theta, phi) in degrees, theta from +z, phi from +x.
DEFAULT_LIGHT = (45.0, 0.0)
#: The scatter view's circles (theta_o in degrees), drawn on PNG output only (the paper's Figure 9).
SCATTER_CIRCLES = (5.0, 30.0, 60.0, 90.0)


def view_cos_theta(view: str, width: int, height: int) -> tuple[np.ndarray, np.ndarray]:
    """
    Cosine of the incidence angle at each pixel (rows from the top) and the mask of pixels that
    show the material.

    ``gradient``: column i at theta = 90 deg (i + 0.5) / W, every row the same.
    ``sphere``: orthographic unit sphere, pixel (i, j) at x = 2 (i + 0.5) / W - 1,
    y = 1 - 2 (j + 0.5) / H, cos theta = sqrt(1 - x^2 - y^2) inside the disc.
    """
    f32 = np.float32
    i = np.arange(width, dtype=f32) + f32(0.5)
    j = np.arange(height, dtype=f32) + f32(0.5)
    if view == "gradient":
        theta = f32(np.pi / 2) * (i / f32(width))
        cos_theta = np.broadcast_to(np.cos(theta), (height, width))
        return cos_theta.astype(np.float64), np.ones((height, width), dtype=bool)
    if view == "sphere":
        x = f32(2.0) * i / f32(width) - f32(1.0)
        y = f32(1.0) - f32(2.0) * j / f32(height)
        r2 = x[None, :] ** 2 + y[:, None] ** 2
        inside = r2 < f32(1.0)
        cos_theta = np.sqrt(np.maximum(f32(1.0) - r2, f32(0.0)))
        return cos_theta.astype(np.float64), inside
    raise ValueError(f"unknown view {view!r} (views: {', '.join(VIEWS)})")


def rim_distance(view: str, width: int, height: int) -> np.ndarray:
    """|r^2 - 1| per pixel for the disc views (inf elsewhere): tests skip the float32 rim."""
    if view not in ("sphere", "lit", "scatter", "textured", "env"):
        return np.full((height, width), np.inf)
    x = 2.0 * (np.arange(width) + 0.5) / width - 1.0
    y = 1.0 - 2.0 * (np.arange(height) + 0.5) / height
    return np.abs(x[None, :] ** 2 + y[:, None] ** 2 - 1.0)


def light_direction(light: tuple[float, float] | None = None) -> np.ndarray:
    """
    The unit vector toward a directional light at ``light = (theta, phi)`` degrees (theta from +z, phi
    from +x; default :data:`DEFAULT_LIGHT`), in float32: the value of the shaders' ``light_direction``.
    """
    theta, phi = DEFAULT_LIGHT if light is None else (float(light[0]), float(light[1]))
    if not (np.isfinite(theta) and np.isfinite(phi)) or not 0.0 <= theta <= 180.0:
        raise ValueError(f"light ({theta:g}, {phi:g}): theta must be in [0, 180] degrees and phi finite")
    theta, phi = np.radians(theta), np.radians(phi)
    direction = np.array([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)])
    return direction.astype(np.float32)


def _f32_normalize(v: np.ndarray) -> np.ndarray:
    return v / np.sqrt(np.sum(v * v, axis=-1, keepdims=True))


def disc(width: int, height: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """p = 2 gl_FragCoord.xy / resolution - 1 per pixel (rows from the top), in float32 as GLSL, and r^2."""
    f32 = np.float32
    fx = np.arange(width, dtype=f32) + f32(0.5)
    fy = f32(height) - (np.arange(height, dtype=f32) + f32(0.5))  # gl_FragCoord.y of row j from the top
    x = np.broadcast_to(f32(2.0) * fx / f32(width) - f32(1.0), (height, width))
    y = np.broadcast_to((f32(2.0) * fy / f32(height) - f32(1.0))[:, None], (height, width))
    return x, y, x * x + y * y


def surface_values(surface, width: int, height: int, raster=None) -> tuple[np.ndarray, np.ndarray]:
    """
    A surface texture's ``(value, sigma)`` per pixel of a ``(height, width)`` image, as the shaders read it
    (``surface_at(surface_uv(...))``): at the sphere's planar coordinates of each disc point, or at a mesh's
    interpolated ones (``raster``: :func:`explorer.views.mesh.rasterise`'s image; float32, as the GL pass writes them).
    """
    if raster is None:
        x, y, _ = disc(width, height)
        return surface.per_pixel(x, y, width, height)
    if surface.prefilter:
        raise ValueError("prefiltering is the sphere's (a footprint per pixel of its planar coordinates), not a mesh's")
    uvs = raster.uvs.astype(np.float32)
    return surface.at_uv(uvs[..., 0], uvs[..., 1])


def _rotate(v: np.ndarray, axis: np.ndarray, angle: np.ndarray) -> np.ndarray:
    """Rodrigues' rotation of ``v`` about the unit ``axis`` (the slice view's ``slice_rotate``), float32."""
    n = axis * np.sum(axis * v, axis=-1, keepdims=True)
    return n + np.cos(angle)[..., None] * (v - n) + np.sin(angle)[..., None] * np.cross(axis, v)


def brdf_view_geometry(view: str, width: int, height: int, light: tuple[float, float] | None = None, slice_phi_d: float = 90.0):
    """
    The arguments of ``BRDF(L, V, N, X, Y)`` at each pixel of a BRDF view, and its mask and factor.

    Returns ``(L, V, N, X, Y, inside, factor)``: five float32 ``(height, width, 3)`` arrays computed as
    the view's shader computes them (``shaders/views/{lit,slice,scatter}.glsl``), the bool mask of pixels
    that show the material (0 elsewhere), and the float64 factor the BRDF is multiplied by: max(0, N.L)
    for ``lit``, 1 for ``slice``, cos(theta_o) for ``scatter``. ``slice_phi_d``: the slice's phi_d in
    degrees (BRDF Explorer's default 90; the shader's ``slice_phi_d`` uniform).
    """
    f32 = np.float32
    shape = (height, width, 3)
    ez = np.broadcast_to(np.array([0, 0, 1], f32), shape)
    if view in ("lit", "scatter"):
        x, y, r2 = disc(width, height)
        inside = r2 < f32(1.0)
        L = np.broadcast_to(light_direction(light), shape)
        if view == "lit":
            N = np.stack([x, y, np.sqrt(np.maximum(f32(1.0) - r2, f32(0.0)))], axis=-1)
            with np.errstate(invalid="ignore", divide="ignore"):  # the poles (0, +-1, 0) lie on the rim
                X = _f32_normalize(np.cross(np.array([0, 1, 0], f32), N))
                Y = _f32_normalize(np.cross(N, X))
            V = ez
            factor = np.maximum(np.sum(N.astype(np.float64) * L, axis=-1), 0.0)
            return L, V, N, X, Y, inside, factor
        r = np.sqrt(r2)
        safe = np.where(r > f32(0.0), r, f32(1.0))
        cos_phi = np.where(r > f32(0.0), x / safe, f32(1.0))
        sin_phi = np.where(r > f32(0.0), y / safe, f32(0.0))
        theta_o = f32(np.pi / 2) * r
        V = np.stack([np.sin(theta_o) * cos_phi, np.sin(theta_o) * sin_phi, np.cos(theta_o)], axis=-1)
        X = np.broadcast_to(np.array([1, 0, 0], f32), shape)
        Y = np.broadcast_to(np.array([0, 1, 0], f32), shape)
        return L, V, ez, X, Y, inside, V[..., 2].astype(np.float64)
    if view == "slice":
        N = np.array([0, 0, 1], f32)
        X = np.array([1, 0, 0], f32)
        Y = np.array([0, 1, 0], f32)
        phi_h, phi_d = f32(0.0), f32(np.radians(slice_phi_d)) if slice_phi_d != 90.0 else f32(np.pi / 2)
        fx = np.arange(width, dtype=f32) + f32(0.5)
        fy = f32(height) - (np.arange(height, dtype=f32) + f32(0.5))
        theta_h = np.broadcast_to(f32(np.pi / 2) * fx / f32(width), (height, width))
        theta_d = np.broadcast_to((f32(np.pi / 2) * (f32(height) - fy) / f32(height))[:, None], (height, width))
        H = np.stack([np.sin(theta_h) * np.cos(phi_h), np.sin(theta_h) * np.sin(phi_h), np.cos(theta_h)], axis=-1)
        D = np.stack([np.sin(theta_d) * np.cos(phi_d), np.sin(theta_d) * np.sin(phi_d), np.cos(theta_d)], axis=-1)
        L = _rotate(_rotate(D, Y, theta_h), N, np.full((height, width), phi_h))
        V = f32(2.0) * np.sum(H * L, axis=-1, keepdims=True) * H - L
        broadcast = [np.broadcast_to(a, shape) for a in (N, X, Y)]
        return (L, V, *broadcast, np.ones((height, width), dtype=bool), np.ones((height, width)))
    raise ValueError(f"{view!r} is not a BRDF view ({', '.join(BRDF_VIEWS)})")


def above_surface(L, V, N) -> np.ndarray:
    """``N.L > 0`` and ``N.V > 0`` for vectors ``(..., 3)``, in their own precision (the shaders': float32)."""
    return (np.sum(N * L, axis=-1) > 0) & (np.sum(N * V, axis=-1) > 0)


def finite_or_zero(f) -> np.ndarray:
    """``f`` as float64 with its NaN and infinite entries set to 0 (finite negative entries kept)."""
    f = np.array(f, dtype=np.float64)
    f[~np.isfinite(f)] = 0.0
    return f


def view_brdf(brdf, L, V, N, X, Y, *per_direction) -> np.ndarray:
    """
    A material's BRDF as every view evaluates it (the twin of ``view_brdf`` in ``shaders/lib/views.glsl``).

    ``brdf(L, V, N, X, Y, *per_direction)`` (a model's ``brdf``, or ``textured_brdf`` with the per-pixel
    D_inc and its spread as ``per_direction``) is evaluated in float64 only where the light and the
    view are both strictly above the surface, ``N.L > 0`` and ``N.V > 0`` (decided in the precision of
    the arguments: float32, as in the shaders); elsewhere the value is 0. A channel that is NaN or
    infinite counts as 0; a finite negative channel is kept (linear sRGB is negative outside the gamut).

    BRDF Explorer's lit sphere (``brdftemplatesphere.frag``) evaluates the BRDF on the dark side too,
    clamps ``max(BRDF, 0)`` and multiplies by the cosine; but ``pow(N.L N.V, k - 1)`` (Minnaert) or
    ``sqrt(N.L N.V)`` (Ward) is NaN there, NaN times 0 is NaN, and GLSL leaves ``max(NaN, 0)``
    undefined: hence the explicit domain and test. Unlike it, negative channels are not clamped: they
    are the out-of-gamut colours of vivid spectra (and what the app's gamut overlay shows).

    Returns
    -------
    ndarray
        ``(..., 3)`` float64, finite.
    """
    above = above_surface(*(np.asarray(a) for a in (L, V, N)))
    result = np.zeros(above.shape + (3,))
    if above.any():
        arguments = [np.broadcast_to(np.asarray(a, dtype=np.float64), above.shape + (3,))[above] for a in (L, V, N, X, Y)]
        extra = [np.broadcast_to(np.asarray(a), above.shape)[above] for a in per_direction]
        with np.errstate(invalid="ignore", divide="ignore", over="ignore"):  # the material's NaN become 0 below
            result[above] = finite_or_zero(brdf(*arguments, *extra))
    return result


def scatter_circles(width: int, height: int) -> np.ndarray:
    """The pixels (bool ``(height, width)``) of the scatter view's 5, 30, 60 and 90 degree circles."""
    x = 2.0 * (np.arange(width) + 0.5) / width - 1.0
    y = 1.0 - 2.0 * (np.arange(height) + 0.5) / height
    r = np.hypot(x[None, :], y[:, None])
    pixel = 2.0 / min(width, height)  # one pixel in disc units
    mask = np.zeros((height, width), dtype=bool)
    for degrees in SCATTER_CIRCLES:
        mask |= np.abs(r - degrees / 90.0) < 0.5 * pixel
    return mask
