"""The Slice and Scatter windows: BRDF Explorer's image slice and outgoing-direction views."""

from __future__ import annotations

import numpy as np

from explorer.rendering import request_view
from explorer.app import data
from explorer.app.camera import light_vector
from explorer.app.panels.base import Panel, record, show_image

SIDE_VIEW_SIZE = 256


class BrdfViewPanel(Panel):
    """A BRDF view of the material at :data:`SIDE_VIEW_SIZE`, with a caption."""

    view = ""
    caption = ""
    dock = "centre"

    def requested(self, uniforms=None, size=(SIDE_VIEW_SIZE, SIDE_VIEW_SIZE)):
        state = self.state
        size = tuple(size)
        job = self.scheduler.job(self.view)
        request_view(job, state.material, state.values, self.view, size, light=light_vector(state.light, state.camera),
                     dragging=self.app.dragging, uniforms=uniforms)
        return job, size

    def progress(self, imgui, job) -> None:
        imgui.text(("done" if job.complete else f"refining {100 * job.progress:.0f}%") + (f"  {job.error}" if job.error else ""))

    def draw(self, imgui) -> None:
        from explorer.app.state import auto_view_size

        imgui.text_wrapped(self.caption)
        avail = imgui.get_content_region_avail()  # the image fills the window, less its progress line
        side = auto_view_size(avail.x, avail.y - 2.0 * imgui.get_text_line_height_with_spacing())
        job, size = self.requested(size=(side, side))
        show_image(self.state, self.scheduler.show(self.view, size, job), size, f"{self.view}_image")
        self.progress(imgui, job)

    def gl_jobs(self) -> list:
        return [self.scheduler.job(self.view)]


def slice_quantity(material) -> str:
    """What the Slice window's colours are: a BRDF, or for a smooth mirror (a Dirac) its reflectance R(theta_d)."""
    from explorer.views.mirror import MIRROR_QUANTITY, is_mirror_only, plotted_quantity

    if is_mirror_only(material):
        return f"{MIRROR_QUANTITY} of the smooth mirror (the weight of its mirror reflection, not a density per sr)"
    return plotted_quantity([False])


class SlicePanel(BrdfViewPanel):
    """
    BRDF Explorer's image slice: theta_h across, theta_d up (both 0-90 deg, on the plot's axes) at the
    phi_d of its slider; shown with the window's exposure and a gamma, or as chroma alone
    (:func:`explorer.app.data.slice_display`).
    """

    title = "Slice"
    view = "slice"
    gl_order = 3

    def __init__(self, app):
        super().__init__(app)
        self._texture = None
        self._shown = None  # (job generation, exposure, gamma, chroma) of the texture

    def draw(self, imgui) -> None:
        from imgui_bundle import implot

        state = self.state
        quantity = slice_quantity(state.material)
        imgui.text_wrapped(f"colour = {quantity}")
        imgui.set_next_item_width(imgui.get_content_region_avail().x * 0.45)
        _, state.slice_phi_d = imgui.slider_float("phi_d", state.slice_phi_d, 0.0, 180.0, "%.1f deg")
        record(state, "slice_phi_d")
        imgui.same_line()
        imgui.set_next_item_width(imgui.get_content_region_avail().x * 0.4)
        _, state.slice_gamma = imgui.slider_float("gamma", state.slice_gamma, 1.0, 4.0, "%.2f")
        record(state, "slice_gamma")
        imgui.same_line()
        _, state.slice_chroma = imgui.checkbox("chroma", state.slice_chroma)
        record(state, "slice_chroma")
        job, size = self.requested({"slice_phi_d": float(np.radians(state.slice_phi_d))})
        if job.complete and job.error is None:
            key = (job.generation, state.exposure, state.slice_gamma, state.slice_chroma)
            if key != self._shown or state.pending_slice_save:
                raw = job.read()
                if state.pending_slice_save:
                    np.save(state.pending_slice_save, raw)
                    state.pending_slice_save = None
                rgba = data.slice_display(raw, state.exposure, state.slice_gamma, state.slice_chroma)
                self._texture = self.app.renderer.resources.replace(self._texture, rgba, dtype="f1", linear=True, origin="slice")
                self._shown = key
                state.slice_report = {"quantity": quantity, "phi_d": state.slice_phi_d, "gamma": state.slice_gamma, "chroma": state.slice_chroma,
                                      "exposure": state.exposure, "size": list(size), "raw_mean": raw.mean(axis=(0, 1)).tolist(),
                                      "shown_mean": rgba[..., :3].mean(axis=(0, 1)).tolist()}
        progressive = self.scheduler.show(self.view, size, job)  # the refining image (exposure, sRGB) until complete
        current = job.complete and self._texture is not None and self._shown is not None and self._shown[0] == job.generation
        # The processed picture holds rows from the top (theta_d = 0 first), the display pass's texture GL's rows
        # from the bottom: each is mapped so that theta_d = 0 is at the bottom, as in BRDF Explorer.
        texture, uv0, uv1 = (self._texture, (0, 1), (1, 0)) if current else (progressive, (0, 0), (1, 1))
        avail = imgui.get_content_region_avail()
        side = max(min(avail.x, avail.y - imgui.get_text_line_height_with_spacing()), 64)
        if implot.begin_plot("##slice", imgui.ImVec2(side, side), implot.Flags_.equal | implot.Flags_.no_legend):
            implot.setup_axes("theta_h (deg)", "theta_d (deg)", implot.AxisFlags_.lock, implot.AxisFlags_.lock)
            implot.setup_axes_limits(0, 90, 0, 90, imgui.Cond_.always)
            implot.plot_image("slice", imgui.ImTextureRef(texture.glo), implot.Point(0, 0), implot.Point(90, 90),
                              imgui.ImVec2(*uv0), imgui.ImVec2(*uv1))
            implot.end_plot()
        record(state, "slice_plot")
        self.progress(imgui, job)


class ScatterPanel(BrdfViewPanel):
    title = "Scatter"
    view = "scatter"
    caption = "outgoing directions, radius ~ theta_o; BRDF*cos theta_o for the light"
    gl_order = 4
