"""
A virtual X display (Debian's ``Xvfb``) for the explorer's window where there is no screen: the tests,
``bench --app`` and the README's screenshot.
"""

from __future__ import annotations

import contextlib
import os
import select
import shutil
import subprocess
import time
from typing import Iterator

SCREEN = "1280x1024x24"


class XvfbUnavailable(RuntimeError):
    """Xvfb is not installed or did not start (one-line message)."""


def _read_display(process: subprocess.Popen, fd: int, timeout_s: float) -> int | None:
    """The display number Xvfb writes to ``fd`` once it accepts connections, or None (it exited or timed out)."""
    deadline, text = time.monotonic() + timeout_s, b""
    while time.monotonic() < deadline and not text.endswith(b"\n"):
        ready, _, _ = select.select([fd], [], [], 0.05)
        if ready:
            chunk = os.read(fd, 32)
            if not chunk:  # Xvfb exited: end of file
                break
            text += chunk
    return int(text) if text.strip().isdigit() else None


@contextlib.contextmanager
def virtual_display(screen: str = SCREEN, timeout_s: float = 10.0) -> Iterator[str]:
    """
    Start ``Xvfb -screen 0 {screen}`` on a free display number, yield ``":N"``, stop it on exit.

    Xvfb picks the number itself (``-displayfd``: it takes the first one whose lock it can create, and
    writes it back once it is ready), so servers started at once, by parallel test workers or other users
    of the machine, never share or steal one another's display.

    Raises :class:`XvfbUnavailable` when Xvfb is missing (``apt-get install xvfb``) or does not start.
    """
    program = shutil.which("Xvfb")
    if program is None:
        raise XvfbUnavailable("Xvfb is not installed (apt-get install xvfb xauth)")
    read_end, write_end = os.pipe()
    try:
        process = subprocess.Popen(
            [program, "-displayfd", str(write_end), "-screen", "0", screen, "-nolisten", "tcp"],
            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, pass_fds=(write_end,),
        )
        os.close(write_end)
        write_end = -1
        number = _read_display(process, read_end, timeout_s)
    finally:
        os.close(read_end)
        if write_end >= 0:
            os.close(write_end)
    if number is None or process.poll() is not None:
        process.kill()
        last_error = (process.stderr.read().decode(errors="replace").strip().splitlines() or ["no output"])[-1]
        process.wait()
        raise XvfbUnavailable(f"Xvfb did not start ({last_error})")
    try:
        yield f":{number}"
    finally:
        process.terminate()
        try:
            process.wait(timeout=5)
        except subprocess.TimeoutExpired:
            process.kill()
            process.wait()


@contextlib.contextmanager
def display_environment() -> Iterator[str]:
    """The current ``DISPLAY`` when there is one, else a virtual one set in ``os.environ`` meanwhile."""
    if os.environ.get("DISPLAY"):
        yield os.environ["DISPLAY"]
        return
    with virtual_display() as display:
        os.environ["DISPLAY"] = display
        try:
            yield display
        finally:
            os.environ.pop("DISPLAY", None)
