"""Help > About and Help > Keyboard and mouse: two small windows, their text here."""

from __future__ import annotations

#: Help > Keyboard and mouse: (input, what it does), in the order a user meets them.
CONTROLS = (
    ("Left-drag on the sphere", "orbit the camera (the light turns with the view)"),
    ("Right-drag on the sphere", "move the light"),
    ("Mouse wheel on the sphere", "zoom (1x to 8x)"),
    ("Ctrl-click on a slider", "reset the parameter to its default"),
    ("Typed field, Enter", "set a parameter to the number typed"),
    ("F5", "reload the material file (a broken file keeps the last good one)"),
    ("F12", "screenshot of the active view (PNG with the exposure, linear .npy)"),
    ("Ctrl+O", "File > Open...: more materials, shown side by side in the plots"),
    ("F1", "this window"),
)


def about_text() -> str:
    """Help > About: the program, its version, what it draws and where the science is."""
    from explorer.resources import package_version

    return (
        f"bragg-explorer {package_version()}\n\n"
        "A real-time explorer of iridescent materials: Bragg mirrors, rough layered Bragg structures and thin "
        "films, drawn by GLSL shaders (BRDF Explorer's .brdf format and our .brd) with a numpy twin of every image.\n\n"
        "Fourneau, Pacanowski & Barla 2024, Interactive Exploration of Vivid Structural Colors; "
        "Belcour & Barla 2017, A Practical Extension to Microfacet Theory for the Modeling of Varying Iridescence; "
        "Bati, Barla & Pacanowski 2021, An Inverse Method for the Exploration of Layered Material Appearance.\n\n"
        "Command line: bragg-explorer --help; tests: python3 -m explorer test."
    )


#: The Help windows' background: opaque (the docked windows' backgrounds are not drawn, see window._style, so
#: a floating window over the Slice plot or the sphere would show them through its text).
HELP_BACKGROUND_ALPHA = 1.0


def draw_help(imgui, state) -> None:
    """The Help menu's windows, while they are open, opaque over the docked ones."""
    from explorer.app.panels.base import record

    centre = imgui.get_main_viewport().get_center()
    if state.show_about:
        imgui.set_next_window_pos(centre, imgui.Cond_.appearing, imgui.ImVec2(0.5, 0.5))
        imgui.set_next_window_size(imgui.ImVec2(520, 0), imgui.Cond_.appearing)
        _opaque(imgui)
        _, state.show_about = imgui.begin("About bragg-explorer", True)
        imgui.pop_style_color()
        _remember_window(imgui, state, "about_window")
        imgui.text_wrapped(about_text())
        record(state, "about_text")
        imgui.end()
    if state.show_controls:
        imgui.set_next_window_pos(centre, imgui.Cond_.appearing, imgui.ImVec2(0.5, 0.5))
        imgui.set_next_window_size(imgui.ImVec2(560, 0), imgui.Cond_.appearing)
        _opaque(imgui)
        _, state.show_controls = imgui.begin("Keyboard and mouse", True)
        imgui.pop_style_color()
        _remember_window(imgui, state, "controls_window")
        if imgui.begin_table("controls", 2):
            for key, action in CONTROLS:
                imgui.table_next_row()
                imgui.table_next_column()
                imgui.text(key)
                imgui.table_next_column()
                imgui.text_wrapped(action)
            imgui.end_table()
        record(state, "controls_table")
        imgui.end()


def _opaque(imgui) -> None:
    """
    The next window's background drawn, in the dark style's popup colour (the window colour's alpha is 0 in the
    app's style); pushed for its ``begin``, which reads it: pop it after.
    """
    colour = imgui.get_style().color_(imgui.Col_.popup_bg)
    imgui.push_style_color(imgui.Col_.window_bg, imgui.ImVec4(colour.x, colour.y, colour.z, HELP_BACKGROUND_ALPHA))
    imgui.set_next_window_bg_alpha(HELP_BACKGROUND_ALPHA)


def _remember_window(imgui, state, label: str) -> None:
    """The current window's screen rectangle under ``label`` (scripted tests look at what it covers)."""
    pos, size = imgui.get_window_pos(), imgui.get_window_size()
    state.rects[label] = (pos.x, pos.y, pos.x + size.x, pos.y + size.y)
