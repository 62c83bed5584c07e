"""
Screenshots: the active view (PNG, 8-bit sRGB with the exposure, and its linear ``.npy``) once it is
complete, and the whole window (the README's picture; the tests' check of what is on screen).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from explorer.files import atomic_output
from explorer.views.images import OutputError, write_image
from explorer.app.scheduler import Scheduler
from explorer.app.state import AppState

SCREENSHOT_DIR = Path("screenshots")


def screenshot_name(state: AppState) -> str:
    """The next free ``screenshots/MATERIAL_VIEW_N.png`` of the active view (``compare`` when Compare is in front)."""
    SCREENSHOT_DIR.mkdir(exist_ok=True)
    stem = f"{Path(state.material_path).stem}_{'compare' if state.active_view == 'compare' else state.main_view()}"
    index = 1
    while (SCREENSHOT_DIR / f"{stem}_{index}.png").exists():
        index += 1
    return str(SCREENSHOT_DIR / f"{stem}_{index}.png")


def window_shot(state: AppState, ctx) -> None:
    """The whole window as a PNG, from the back buffer before it is swapped."""
    from PIL import Image

    import OpenGL.GL as gl

    # PyOpenGL, not moderngl: moderngl reads "colour attachment 0", which the window's own
    # framebuffer does not have (GL_INVALID_OPERATION).
    width, height = ctx.screen.size
    gl.glBindFramebuffer(gl.GL_READ_FRAMEBUFFER, 0)
    gl.glReadBuffer(gl.GL_BACK)
    gl.glPixelStorei(gl.GL_PACK_ALIGNMENT, 1)
    data = gl.glReadPixels(0, 0, width, height, gl.GL_RGB, gl.GL_UNSIGNED_BYTE)
    pixels = np.frombuffer(data, dtype=np.uint8).reshape(height, width, 3)[::-1]
    with atomic_output(state.pending_window_shot, (".png",)) as temporary:
        Image.fromarray(np.ascontiguousarray(pixels), mode="RGB").save(temporary, format="PNG")
    state.screenshots.append(state.pending_window_shot)
    state.pending_window_shot = None


def take_screenshot(state: AppState, scheduler: Scheduler) -> None:
    """Write the active view asked for (``state.pending_screenshot``) once it is complete."""
    if state.pending_screenshot is None:
        return
    samples = None
    view = "env" if state.mode == "env" else state.main_view()
    if state.active_view == "compare" and state.compare.on:
        image = compare_image(state, scheduler)
        if image is None:
            return  # written when both sides are refined
        view = "compare"
    elif state.mode == "env":
        render = scheduler.env.render
        if render is None or render.material is not state.material or render.samples == 0 or render._band_rows:
            return  # written at the first whole sample of the material shown (every pixel the same count)
        image = np.asarray(render.image(), dtype=np.float32)
        samples = render.samples
    else:
        job = scheduler.job("main")
        if job.error is not None:
            state.status = f"no screenshot: {job.error}"
            state.pending_screenshot = None
            return
        if not job.complete:
            return  # written when the image is refined (the window stays responsive meanwhile)
        image = job.read()
    path = Path(state.pending_screenshot)
    state.pending_screenshot = None
    try:
        tonemap = state.tonemap_for(scheduler.job("compare_a").view if view == "compare" else view)
        write_image(image, path.with_suffix(".png"), exposure=state.exposure, tonemap=tonemap)
        write_image(image, path.with_suffix(".npy"))
    except OutputError as error:
        state.status = str(error)
        return
    state.screenshots.append(str(path.with_suffix(".png")))
    state.screenshot_info[str(path.with_suffix(".png"))] = {
        "material": str(state.material_path), "view": view,
        "values": state.json_values(), "samples": samples, "inverse": state.inverse,
    }
    state.status = f"wrote {path.with_suffix('.png')} and {path.with_suffix('.npy')}"


def compare_image(state: AppState, scheduler: Scheduler):
    """
    The Compare window's split image as it shows it, linear: A left of the middle column, B from it on (the display
    pass's ``x >= split``); None until both are complete. An error is reported in the status line (and the shot dropped).
    """
    a, b = scheduler.job("compare_a"), scheduler.job("compare_b")
    for job in (a, b):
        if job.error is not None:
            state.status = f"no screenshot: {job.error}"
            state.pending_screenshot = None
            return None
    if not (a.complete and b.complete):
        return None
    left, right = a.read(), b.read()
    width = left.shape[1]
    columns = (np.arange(width) + 0.5) / width >= 0.5
    return np.where(columns[None, :, None], right, left)
