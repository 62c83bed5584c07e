"""The app's font draws the Greek letters and symbols its labels use (ImGui's default font is ASCII only)."""

from imgui_bundle import imgui

from explorer.app.window import _fonts

#: Characters the app's labels draw: the accuracy line (ΔE2000, ≤, >), angles, wavelengths, factors.
LABEL_CHARACTERS = "ΔE≤≥θλ°×αδΛ"


def _font(with_fallback: bool):
    context = imgui.create_context()
    if with_fallback:
        _fonts(imgui)
    else:
        imgui.get_io().fonts.add_font_default()
    return context, imgui.get_io().fonts.fonts[0]


def test_default_font_alone_lacks_the_labels_symbols():
    context, font = _font(False)
    try:
        assert not font.is_glyph_in_font(ord("Δ"))  # what the app showed as '?'
    finally:
        imgui.destroy_context(context)


def test_app_font_has_every_label_character():
    context, font = _font(True)
    try:
        missing = [c for c in LABEL_CHARACTERS if not font.is_glyph_in_font(ord(c))]
        assert not missing, f"the app's font lacks {missing}"
    finally:
        imgui.destroy_context(context)
