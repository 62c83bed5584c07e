"""
A virtual X display (Debian's ``Xvfb``) for the explorer's window where there is no screen: the tests,
``bench --app`` and the README's screenshot.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import subprocess
import time
from pathlib import Path
from typing import Iterator

SCREEN = "1280x1024x24"


class XvfbUnavailable(RuntimeError):
    """Xvfb is not installed or did not start (one-line message)."""


def _free_display(start: int = 90) -> int:
    """A display number with neither a lock file nor a socket."""
    for number in range(start, start + 200):
        if not Path(f"/tmp/.X{number}-lock").exists() and not Path(f"/tmp/.X11-unix/X{number}").exists():
            return number
    raise XvfbUnavailable("no free X display number in :90-:289")


@contextlib.contextmanager
def virtual_display(screen: str = SCREEN, timeout_s: float = 10.0) -> Iterator[str]:
    """
    Start ``Xvfb :N -screen 0 {screen}`` on a free display number, yield ``":N"``, stop it on exit.

    Raises :class:`XvfbUnavailable` when Xvfb is missing (``apt-get install xvfb``) or does not start.
    """
    program = shutil.which("Xvfb")
    if program is None:
        raise XvfbUnavailable("Xvfb is not installed (apt-get install xvfb xauth)")
    last_error = ""
    for _attempt in range(3):
        number = _free_display()
        process = subprocess.Popen(
            [program, f":{number}", "-screen", "0", screen, "-nolisten", "tcp"],
            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
        )
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline and process.poll() is None:
            if Path(f"/tmp/.X11-unix/X{number}").exists():
                break
            time.sleep(0.05)
        if process.poll() is None and Path(f"/tmp/.X11-unix/X{number}").exists():
            try:
                yield f":{number}"
            finally:
                process.terminate()
                try:
                    process.wait(timeout=5)
                except subprocess.TimeoutExpired:
                    process.kill()
                    process.wait()
            return
        process.kill()
        last_error = (process.stderr.read().decode(errors="replace").strip().splitlines() or ["no output"])[-1]
        process.wait()
    raise XvfbUnavailable(f"Xvfb did not start ({last_error})")


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
