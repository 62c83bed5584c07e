"""
What the benchmarks and accuracy studies share: figure output, the Bragg mirrors' grids, progress lines.
"""

from __future__ import annotations

import sys

import numpy as np

from explorer import files

#: What matplotlib's figures (``accuracy --plot``, ``figure --out``) and Figure 4's strips are written as.
FIGURE_SUFFIXES = (".png", ".pdf", ".svg")
STRIP_SUFFIXES = (".png",)


def save_figure(figure, path, **options) -> None:
    """A matplotlib figure to ``path`` (a format of :data:`FIGURE_SUFFIXES`, by its suffix), atomically; left open."""
    files.save_figure(figure, path, FIGURE_SUFFIXES, close=False, **options)

BENCH_LAMBDAS = (244.0, 500.0, 988.0)
FIGURE4_LAMBDAS = (244.0, 500.0, 988.0)
FIGURE4_DELTAS = (0.25, 0.5, 0.75)
#: Incidence angles of the accuracy studies: theta in [0, 89.5] degrees.
THETA_DEGREES = np.linspace(0.0, 89.5, 180)


def _progress(message: str) -> None:
    print(message, file=sys.stderr, flush=True)
