"""Errors that point at a place in a file: what bad input turns into before it reaches the user."""

from __future__ import annotations

import os


def did_you_mean(word: str, choices) -> str:
    """``" (did you mean 'X'?)"`` for the closest of ``choices`` to a mistyped ``word`` (difflib), else ``""``."""
    import difflib

    close = difflib.get_close_matches(str(word), [str(c) for c in choices], n=1, cutoff=0.6)
    return f" (did you mean {close[0]!r}?)" if close else ""


#: Files the user named otherwise, by resolved path: a built-in material typed by name is reported by that name
#: (:func:`explorer.resources.material_path` records it), not by the absolute path of its installed file.
_SHOWN_AS: dict[str, str] = {}


def show_path_as(path: str | os.PathLike[str], typed: str) -> None:
    """Report errors located in ``path`` under ``typed``, the text the user named it by."""
    _SHOWN_AS[os.fspath(path)] = typed


class LocatedError(Exception):
    """
    Something is wrong at a place in a file.

    Parameters
    ----------
    path : str or path-like
        The file (or another origin, such as ``"--set"`` or a ``<name>`` for generated text).
    line : int or None
        1-based line in ``path``, or None when the problem has no line.
    message : str
        What is wrong.

    Notes
    -----
    ``str(error)`` is always one line, ``"{path}:{line}: {message}"`` or ``"{path}: {message}"``, so that
    editors and terminals can jump to it.
    """

    def __init__(self, path: str | os.PathLike[str], line: int | None, message: str) -> None:
        # Pass all three to Exception so that the error pickles (multiprocessing).
        super().__init__(os.fspath(path), line, message)
        self.path: str = os.fspath(path)
        self.line: int | None = line
        self.message: str = message

    def __str__(self) -> str:
        path = _SHOWN_AS.get(self.path, self.path)
        where = path if self.line is None else f"{path}:{self.line}"
        return " ".join(f"{where}: {self.message}".splitlines())


class OutputError(Exception):
    """An output file cannot be written (one line naming it); raised before any work where it can be."""
