"""What every panel is: a docked window with a title, drawn each frame it is visible, and the GL views
it wants advanced (see :mod:`explorer.app.panels`)."""

from __future__ import annotations

from explorer.app.camera import sphere_mouse


class Panel:
    """
    A docked ImGui window of the app.

    Attributes
    ----------
    title : str
        The window's title (and what a script's ``{"focus": TITLE}`` names).
    dock : str
        Where the layout docks it: ``left``, ``centre``, ``right_top`` or ``right_bottom``.
    gl_order : int
        Its views' place in the frame's GL work (lower first: the sphere's is 0).
    """

    title = ""
    dock = "centre"
    gl_order = 100

    def __init__(self, app):
        self.app = app
        self.state = app.state
        self.scheduler = app.scheduler

    def draw(self, imgui) -> None:
        """The window's contents (between ImGui's ``begin`` and ``end``)."""
        raise NotImplementedError

    def gl_jobs(self) -> list:
        """The progressive views to advance this frame, in order (when the window is visible)."""
        return []

    def after_gl(self) -> None:
        """Work on the frame's finished views (when the window is visible)."""


def record(state, label: str) -> None:
    """Remember the last item's screen rectangle under ``label`` (for scripted input)."""
    from imgui_bundle import imgui

    lo, hi = imgui.get_item_rect_min(), imgui.get_item_rect_max()
    state.rects[label] = (lo.x, lo.y, hi.x, hi.y)
    top, size = imgui.get_window_pos(), imgui.get_window_size()
    if top.y <= lo.y and hi.y <= top.y + size.y:  # wholly inside its window (a half-hidden slider can't be dragged)
        state.hidden.discard(label)
    else:
        state.hidden.add(label)
        if label == state.script_target:
            # A scripted click or drag on an item scrolled out of its panel: scroll it into view, as a user would.
            imgui.set_scroll_here_y(0.5)


def combo(state, label: str, shown: str, options, current, item: str, recorded_as: str):
    """
    An ImGui combo of ``options`` (``(key, text)`` pairs, ``current`` selected) showing ``shown``; each entry
    is recorded as ``item:key`` and the combo as ``recorded_as`` (scripted input). Returns the key clicked,
    or None.
    """
    from imgui_bundle import imgui

    chosen = None
    if imgui.begin_combo(label, shown):
        for key, text in options:
            clicked, _ = imgui.selectable(text, key == current)
            record(state, f"{item}:{key}")
            if clicked:
                chosen = key
        imgui.end_combo()
    record(state, recorded_as)
    return chosen


def show_image(state, texture, size, label: str, interactive: bool = False, side: float = 0.0) -> None:
    """
    An image fitted to the window (less ``side`` pixels on its right, for a colour bar), flipped to
    rows-from-the-top, zoomed about its centre when ``interactive``.
    """
    from imgui_bundle import imgui

    avail = imgui.get_content_region_avail()
    scale = min(1.0, max(avail.x - side, 16) / size[0], max(avail.y - 24, 16) / size[1]) if size[0] > 0 else 1.0
    shown = imgui.ImVec2(size[0] * scale, size[1] * scale)
    half = 0.5 / (state.zoom if interactive else 1.0)
    imgui.image(imgui.ImTextureRef(texture.glo), shown, imgui.ImVec2(0.5 - half, 0.5 + half), imgui.ImVec2(0.5 + half, 0.5 - half))
    record(state, label)
    if interactive:
        sphere_mouse(state, imgui, label)


def checkbox_width(imgui, label: str) -> float:
    """The width a checkbox labelled ``label`` takes (its box, the gap, the text)."""
    style = imgui.get_style()
    box = imgui.get_frame_height()
    return box + style.item_inner_spacing.x + imgui.calc_text_size(label.split("##")[0]).x


def button_width(imgui, label: str) -> float:
    """The width a button labelled ``label`` takes (its text and frame padding)."""
    return imgui.calc_text_size(label.split("##")[0]).x + 2.0 * imgui.get_style().frame_padding.x


def flow(imgui, width: float) -> None:
    """Put the next item of ``width`` pixels on the current line when it fits there, else on the next (no item cut)."""
    right = imgui.get_item_rect_max().x + imgui.get_style().item_spacing.x + width
    # Before same_line the cursor is at the start of the next line: the region's right edge is avail.x beyond it.
    limit = imgui.get_cursor_screen_pos().x + imgui.get_content_region_avail().x
    if right <= limit:
        imgui.same_line()
