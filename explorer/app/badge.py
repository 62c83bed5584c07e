"""
The Parameters window's accuracy badge (:mod:`explorer.materials.accuracy`), computed off the UI thread.

The badge needs the mirror's converged table (0.1-3 s the first time, cached per mirror) and each
method's colours at the gradient's 90 angles (tens of ms): too slow for a frame. A daemon thread
computes it for the newest values once no slider is dragged; the window shows the last result meanwhile.
"""

from __future__ import annotations

import threading

from explorer.materials.accuracy import AccuracyBadge, accuracy_badge


class BadgeWorker:
    """The newest values' :class:`AccuracyBadge`, computed on a daemon thread (one at a time)."""

    def __init__(self):
        self._lock = threading.Lock()
        self._thread: threading.Thread | None = None
        self._key = None  # the values of the badge below
        self._badge: AccuracyBadge | None = None
        self._error: str = ""

    @staticmethod
    def key(material, values) -> tuple | None:
        try:
            key = (id(material), tuple(sorted((k, str(v)) for k, v in values.items())))
            hash(key)
            return key
        except TypeError:
            return None

    def request(self, material, values, dragging: bool) -> tuple[AccuracyBadge | None, bool]:
        """The last badge computed, and whether it is that of ``values`` (else one is on its way)."""
        key = self.key(material, values)
        with self._lock:
            current = key is not None and key == self._key
            badge, busy = self._badge, self._thread is not None and self._thread.is_alive()
        if not current and not busy and not dragging and key is not None:
            thread = threading.Thread(target=self._compute, args=(material, dict(values), key), daemon=True,
                                      name="accuracy-badge")
            with self._lock:
                self._thread = thread
            thread.start()
        return badge, current

    def _compute(self, material, values, key) -> None:
        try:
            badge, error = accuracy_badge(material, values), ""
        except Exception as exc:  # noqa: BLE001 - shown in the window, never fatal to the UI
            badge, error = None, f"accuracy badge: {exc}"
        with self._lock:
            self._badge, self._key, self._error = badge, key, error

    @property
    def error(self) -> str:
        return self._error

    def wait(self, timeout: float = 30.0) -> None:
        """Until the running computation (if any) ends (tests)."""
        thread = self._thread
        if thread is not None:
            thread.join(timeout)
