"""The Slice and Scatter windows: BRDF Explorer's image slice and outgoing-direction views."""

from __future__ import annotations

from explorer.app.camera import light_vector
from explorer.app.panels.base import Panel, show_image

SIDE_VIEW_SIZE = 256


class BrdfViewPanel(Panel):
    """A BRDF view of the material at :data:`SIDE_VIEW_SIZE`, with a caption."""

    view = ""
    caption = ""
    dock = "centre"

    def draw(self, imgui) -> None:
        state = self.state
        imgui.text(self.caption)
        size = (SIDE_VIEW_SIZE, SIDE_VIEW_SIZE)
        job = self.scheduler.job(self.view)
        job.request(state.material, state.values, self.view, size, light=light_vector(state.light, state.camera), dragging=self.app.dragging)
        show_image(state, self.scheduler.show(self.view, size, job), size, f"{self.view}_image")
        imgui.text(("done" if job.complete else f"refining {100 * job.progress:.0f}%") + (f"  {job.error}" if job.error else ""))

    def gl_jobs(self) -> list:
        return [self.scheduler.job(self.view)]


class SlicePanel(BrdfViewPanel):
    title = "Slice"
    view = "slice"
    caption = "theta_h across (0-90 deg), theta_d down (0-90 deg), phi_d = 90 deg"
    gl_order = 3


class ScatterPanel(BrdfViewPanel):
    title = "Scatter"
    view = "scatter"
    caption = "outgoing directions, radius ~ theta_o; BRDF*cos theta_o for the light"
    gl_order = 4
