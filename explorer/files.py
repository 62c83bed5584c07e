"""
Output files, written atomically: every file the package writes (renders, figures, plots, the app's
saves and screenshots, the report, the table cache) goes through :func:`atomic_output`.

The data goes to a hidden temporary file in the target's own folder, which replaces the target by
``os.replace`` once it is complete (a rename within one file system: readers see the old file or the
new one, never a partial one). On any exit before that (an exception, a full disk, Ctrl-C, or SIGTERM,
which the CLI turns into ``SystemExit``) the temporary file is removed and the target is untouched.
:func:`check_output` validates a path (suffix, folder) before any work is done.

Standard library only, no GL: :mod:`explorer.tables` writes its cache through it (:func:`save_figure` takes a
matplotlib figure, and imports pyplot only to close it).
"""

from __future__ import annotations

import contextlib
import os
import tempfile
from collections.abc import Iterator, Sequence
from pathlib import Path

from explorer.errors import OutputError

__all__ = ["OutputError", "check_output", "atomic_output", "write_bytes_atomic", "write_text_atomic", "save_figure",
           "describe_suffixes"]


def describe_suffixes(suffixes: Sequence[str]) -> str:
    """``".png, .npy or .exr"``."""
    items = list(suffixes)
    return items[0] if len(items) == 1 else ", ".join(items[:-1]) + " or " + items[-1]


def check_output(out: str | os.PathLike[str], suffixes: Sequence[str] | None = None) -> Path:
    """
    The folder ``out`` will be written to, or a one-line :class:`OutputError` before any work.

    Parameters
    ----------
    out : path-like
        The output file.
    suffixes : sequence of str, optional
        The formats accepted (lower case, with the dot), named in the error when ``out`` has another.

    Raises
    ------
    OutputError
        Another suffix, a folder, a missing or read-only parent folder.
    """
    out = Path(out)
    if suffixes is not None and out.suffix.lower() not in suffixes:
        got = f"{out.suffix!r} is not one" if out.suffix else "it has no suffix"
        raise OutputError(f"{out}: the output must end in {describe_suffixes(suffixes)} ({got})")
    if out.is_dir():
        raise OutputError(f"{out}: is a directory")
    directory = out.parent if str(out.parent) else Path(".")
    if not directory.is_dir():
        raise OutputError(f"{out}: directory {directory} does not exist")
    if not os.access(directory, os.W_OK):
        raise OutputError(f"{out}: directory {directory} is not writable")
    return directory


def _umask() -> int:
    umask = os.umask(0)
    os.umask(umask)
    return umask


@contextlib.contextmanager
def atomic_output(out: str | os.PathLike[str], suffixes: Sequence[str] | None = None) -> Iterator[Path]:
    """
    A temporary path next to ``out`` to write to; it replaces ``out`` when the block ends normally.

    The temporary file keeps ``out``'s suffix (writers that pick a format by suffix, such as OpenCV's,
    write the right one). Whatever ends the block early (any exception, ``KeyboardInterrupt`` and
    ``SystemExit`` included) removes it and leaves ``out`` as it was.

    Raises
    ------
    OutputError
        ``out`` cannot be written (see :func:`check_output`), or an ``OSError`` while writing
        (a full disk: ``ENOSPC``, a file size limit: ``EFBIG``), one line naming ``out``.
    """
    out = Path(out)
    directory = check_output(out, suffixes)
    try:
        handle, name = tempfile.mkstemp(prefix=f".{out.name}.", suffix=f".tmp{out.suffix}", dir=directory)
    except OSError as error:
        raise OutputError(f"{out}: cannot write ({error.strerror or error})") from None
    os.close(handle)
    temporary = Path(name)
    try:
        yield temporary
        os.chmod(temporary, 0o666 & ~_umask())  # mkstemp makes private files; an output follows the umask
        os.replace(temporary, out)
    except OSError as error:
        raise OutputError(f"{out}: cannot write ({error.strerror or error})") from None
    finally:
        with contextlib.suppress(OSError):
            temporary.unlink(missing_ok=True)


def write_bytes_atomic(out: str | os.PathLike[str], data: bytes, suffixes: Sequence[str] | None = None) -> None:
    """``data`` into ``out`` through :func:`atomic_output`."""
    with atomic_output(out, suffixes) as temporary:
        with open(temporary, "wb") as stream:
            stream.write(data)


def write_text_atomic(out: str | os.PathLike[str], text: str, suffixes: Sequence[str] | None = None) -> None:
    """``text`` (UTF-8) into ``out`` through :func:`atomic_output`."""
    write_bytes_atomic(out, text.encode("utf-8"), suffixes)


def save_figure(figure, out: str | os.PathLike[str], suffixes: Sequence[str] | None = (".png",), close: bool = True,
                format: str | None = None, **options) -> None:
    """
    A matplotlib ``figure`` into ``out`` through :func:`atomic_output` (its suffix one of ``suffixes``), in
    ``format`` (default: the one the suffix names); ``options`` go to ``savefig`` (``dpi``). ``close``: the figure
    is closed afterwards, also when saving fails (pyplot keeps every open figure alive).
    """
    try:
        with atomic_output(out, suffixes) as temporary:
            with open(temporary, "wb") as stream:
                figure.savefig(stream, format=format or Path(out).suffix.lower()[1:], **options)
    finally:
        if close:
            import matplotlib.pyplot as plt  # lazily: the package's bottom layer needs no matplotlib

            plt.close(figure)
