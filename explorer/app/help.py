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


def draw_help(imgui, state) -> None:
    """The Help menu's windows, while they are open."""
    from explorer.app.panels.base import record

    centre = imgui.get_main_viewport().get_center()
    if state.show_about:
        imgui.set_next_window_pos(centre, imgui.Cond_.appearing, imgui.ImVec2(0.5, 0.5))
        imgui.set_next_window_size(imgui.ImVec2(520, 0), imgui.Cond_.appearing)
        _, state.show_about = imgui.begin("About bragg-explorer", True)
        imgui.text_wrapped(about_text())
        record(state, "about_text")
        imgui.end()
    if state.show_controls:
        imgui.set_next_window_pos(centre, imgui.Cond_.appearing, imgui.ImVec2(0.5, 0.5))
        imgui.set_next_window_size(imgui.ImVec2(560, 0), imgui.Cond_.appearing)
        _, state.show_controls = imgui.begin("Keyboard and mouse", True)
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
