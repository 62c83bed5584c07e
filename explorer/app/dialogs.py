"""
File > Open...: a native multi-select file dialog (imgui-bundle's portable-file-dialogs: zenity, kdialog,
... on Linux), polled each frame so the window keeps drawing while it is open.

Where no dialog program exists (a bare machine, Xvfb) the same menu opens an ImGui window with a path
field (several paths separated by ``;``). A scripted session answers the dialog instead of a person:
its ``{"dialog": [PATH, ...]}`` action queues the answer (``AppState.dialog_answers``), which the next
File > Open... takes without starting any program.
"""

from __future__ import annotations

import shutil

from explorer.resources import MATERIAL_SUFFIXES

#: The programs portable-file-dialogs drives on Linux (any one on the PATH is enough).
DIALOG_PROGRAMS = ("zenity", "matedialog", "qarma", "kdialog")


def native_dialog_available() -> bool:
    """Whether portable-file-dialogs can show a dialog here (imported, and one of its programs installed)."""
    try:
        from imgui_bundle import portable_file_dialogs  # noqa: F401
    except ImportError:
        return False
    return any(shutil.which(program) for program in DIALOG_PROGRAMS)


def split_paths(text: str) -> list[str]:
    """The fallback field's paths: separated by ``;`` (a path may hold spaces), blanks dropped."""
    return [part.strip() for part in text.split(";") if part.strip()]


class OpenDialog:
    """
    The open-materials dialog: :meth:`start` it, then :meth:`poll` it every frame until it returns the
    chosen paths (a list, possibly empty when cancelled) and is closed again.

    ``log`` records how each dialog was answered (``scripted``, ``native``, ``field``), for the report.
    """

    def __init__(self):
        self._native = None  # a pending portable_file_dialogs.open_file
        self._field_open = False
        self._field_text = ""
        self._scripted: list | None = None
        self.log: list[str] = []

    @property
    def open(self) -> bool:
        return self._native is not None or self._field_open or self._scripted is not None

    def start(self, state) -> None:
        """Open the dialog (nothing when one is open already)."""
        if self.open:
            return
        if state.dialog_answers:
            self._scripted = list(state.dialog_answers.pop(0))
            return
        if native_dialog_available():
            from imgui_bundle import portable_file_dialogs as pfd

            filters = ["Materials", " ".join(f"*{suffix}" for suffix in MATERIAL_SUFFIXES), "All files", "*"]
            self._native = pfd.open_file("Open materials", "", filters, pfd.opt.multiselect)
            return
        self._field_open = True

    def poll(self, imgui, state) -> list[str] | None:
        """The chosen paths once the dialog is answered (``[]`` when cancelled), else None."""
        if self._scripted is not None:
            paths, self._scripted = self._scripted, None
            self.log.append(f"scripted: {len(paths)} paths")
            return paths
        if self._native is not None:
            if not self._native.ready(0):
                return None
            paths, self._native = list(self._native.result()), None
            self.log.append(f"native: {len(paths)} paths")
            return paths
        if self._field_open:
            return self._field(imgui, state)
        return None

    def _field(self, imgui, state) -> list[str] | None:
        """The fallback: a window with a path field (``;`` between paths), Open and Cancel."""
        from explorer.app.panels.base import record

        imgui.set_next_window_pos(imgui.get_main_viewport().get_center(), imgui.Cond_.appearing, imgui.ImVec2(0.5, 0.5))
        imgui.set_next_window_size(imgui.ImVec2(560, 0), imgui.Cond_.appearing)
        _, self._field_open = imgui.begin("Open materials", True)
        answer = None
        imgui.text_wrapped("No file dialog program (zenity, kdialog) here: type the paths, separated by ';'.")
        entered, self._field_text = imgui.input_text("paths", self._field_text, imgui.InputTextFlags_.enter_returns_true)
        record(state, "open_dialog:paths")
        if imgui.button("Open") or entered:
            answer = split_paths(self._field_text)
        record(state, "open_dialog:open")
        imgui.same_line()
        if imgui.button("Cancel"):
            answer = []
        imgui.end()
        if answer is not None or not self._field_open:
            self._field_open = False
            self.log.append(f"field: {len(answer or [])} paths")
            return answer or []
        return None
