"""
The plot views' outputs (:mod:`explorer.views.plots`): a chart drawn by matplotlib (``.png``), or the plotted
values (``.npy``: a curve's rows are ``(angle in degrees, value per channel...)``, the lobe's array is
``(theta_o, phi_o, value per channel...)`` per direction), written atomically.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from explorer.files import atomic_output, check_output, save_figure
from explorer.views.plots import ABSCISSAE, PlotSettings, abscissa, lobe_directions

#: The chart's size in inches and dots per inch (640 x 440 pixels).
FIGURE_SIZE = (6.4, 4.4)
DPI = 100
#: Line colours by channel.
CHANNEL_COLOURS = {"r": "tab:red", "g": "tab:green", "b": "tab:blue", "luminance": "black"}


def _channels(settings: PlotSettings) -> tuple[str, ...]:
    return ("r", "g", "b") if settings.channel == "rgb" else (settings.channel,)


def plot_table(view: str, values: np.ndarray, settings: PlotSettings) -> np.ndarray:
    """
    The ``.npy`` of a plot: ``values`` are the plotted values ``(height, width, k)``
    (:func:`explorer.views.plots.plotted`); a curve gives ``(width, 1 + k)``, the lobe ``(height * width, 2 + k)``.
    """
    height, width = values.shape[:2]
    if view == "lobe3d":
        theta_o, phi_o = lobe_directions(width, height)
        columns = [np.degrees(theta_o).reshape(-1, 1), np.degrees(phi_o).reshape(-1, 1), values.reshape(height * width, -1)]
        return np.concatenate(columns, axis=1).astype(np.float32)
    return np.concatenate([abscissa(view, width)[:, None], values[0]], axis=1).astype(np.float32)


def _ylabel(view: str, settings: PlotSettings, mirror: bool = False) -> str:
    from explorer.views.mirror import plotted_quantity

    quantity = "albedo" if view == "albedo" else plotted_quantity([mirror])
    if settings.ndotl:
        quantity += " x cos theta_i" if view == "albedo" else " x N.L"
    if settings.channel == "luminance":
        quantity = f"luminance of {quantity}"
    return f"log10(1 + {quantity})" if settings.log else quantity


def _settings_note(view: str, settings: PlotSettings, light) -> str:
    notes = {"theta_v": f"phi_v = {settings.phi_v:g} deg", "theta_h": f"theta_d = {settings.theta_d:g} deg, phi_d = 90 deg",
             "theta_d": f"theta_h = {settings.theta_h:g} deg, phi_d = 90 deg", "albedo": "directional albedo", "lobe3d": ""}
    note = notes[view]
    if light is not None and view in ("theta_v", "lobe3d"):
        note = ", ".join(part for part in (f"light ({light[0]:g}, {light[1]:g}) deg", note) if part)
    return note


def write_plot(view: str, values: np.ndarray, settings: PlotSettings, out: Path, title: str = "", light=None,
               mirror: bool = False) -> None:
    """
    Write a plot view: ``values`` are what it plots ``(height, width, k)`` (:func:`explorer.views.plots.plotted`);
    ``.npy`` gets :func:`plot_table`, ``.png`` a matplotlib chart (Agg), ``title`` above it; ``light`` (degrees) is
    drawn in the lobe and named in the caption; ``mirror``: a smooth mirror's (its values are a reflectance).
    """
    check_output(out, (".png", ".npy"))
    if Path(out).suffix.lower() == ".npy":
        with atomic_output(out, (".npy",)) as temporary:
            with open(temporary, "wb") as stream:
                np.save(stream, plot_table(view, values, settings))
        return
    save_figure(chart(view, values, settings, title, light, mirror), out, dpi=DPI)


def chart(view: str, values: np.ndarray, settings: PlotSettings, title: str = "", light=None, mirror: bool = False):
    """The matplotlib figure of a plot view (curves against their angle, or the 3D lobe's surface)."""
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    figure = plt.figure(figsize=FIGURE_SIZE, dpi=DPI)
    note = _settings_note(view, settings, light)
    figure.suptitle("\n".join(part for part in (title, note) if part), fontsize=9)
    channels = _channels(settings)
    if view == "lobe3d":
        axes = figure.add_subplot(projection="3d")
        height, width = values.shape[:2]
        theta_o, phi_o = lobe_directions(width, height)
        # The radius in each direction: the plotted value (a channel, or the luminance of the RGB lobe).
        radius = values[..., 0] if len(channels) == 1 else values.mean(axis=-1)
        radius = np.maximum(radius, 0.0)
        x, y, z = (radius * np.sin(theta_o) * np.cos(phi_o), radius * np.sin(theta_o) * np.sin(phi_o), radius * np.cos(theta_o))
        colour = CHANNEL_COLOURS[channels[0]] if len(channels) == 1 else "tab:orange"
        axes.plot_surface(x, y, z, color=colour, alpha=0.8, linewidth=0.2, edgecolor="grey", shade=True)
        extent = float(max(radius.max(), 1e-6))
        if light is not None:  # the incident direction, as BRDF Explorer draws it
            t, p = np.radians(light[0]), np.radians(light[1])
            axes.plot([0, extent * np.sin(t) * np.cos(p)], [0, extent * np.sin(t) * np.sin(p)], [0, extent * np.cos(t)],
                      color="gold", linewidth=2, label="incident")
            axes.legend(loc="upper left", fontsize=8)
        axes.set_xlim(-extent, extent)
        axes.set_ylim(-extent, extent)
        axes.set_zlim(0, extent)
        axes.set_xlabel("x")
        axes.set_ylabel("y")
        axes.set_zlabel(_ylabel(view, settings, mirror), fontsize=8)
        return figure
    axes = figure.add_subplot()
    angle = abscissa(view, values.shape[1])
    for k, name in enumerate(channels):
        axes.plot(angle, values[0, :, k], color=CHANNEL_COLOURS[name], linewidth=1.5, label=name)
    label, first, last = ABSCISSAE[view]
    axes.set_xlim(first, last)
    axes.set_xlabel(label)
    axes.set_ylabel(_ylabel(view, settings, mirror))
    axes.grid(True, alpha=0.3)
    if len(channels) > 1 or channels[0] == "luminance":
        axes.legend(fontsize=8)
    figure.tight_layout()
    return figure
