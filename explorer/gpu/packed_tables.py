"""
A 1D RGB table over cos theta packed for one texel fetch a lookup: texel ``i`` of an
RGBA32UI buffer texture holds the interval between entries ``i`` and ``i + 1``, both entries' channels as
signed 16-bit codes and the interval's own scale. GLSL twin: ``shaders/lib/bragg.glsl``'s
``packed_tabulated_rgb`` (the tabulated method's ``tabulated_rgb`` on a ``usamplerBuffer``).

Why: on Mesa's llvmpipe each texel fetch is an out-of-line call, and the two an exact float lookup needs
cost about as much as Schlick's whole pixel; one fetch and 16-bit decoding cost ~20% less CPU per sphere
frame (docs/performance.md, *Tabulated shading: one fetch*). The interpolation is still linear in
cos theta in float; only the entries are rounded, to half a code of the interval's largest |channel|:
<= 1.53e-5 of the local brightest channel, far under the tabulated method's 4e-4.
"""

from __future__ import annotations

import numpy as np

#: The largest code: channels are ``code * scale`` with ``|code| <= PACKED_CODE_MAX`` (signed 16 bits).
PACKED_CODE_MAX = 32767


def pack_table_intervals(table: np.ndarray) -> np.ndarray:
    """
    ``(n, 3)`` float RGB entries at cos theta = k / (n - 1) -> ``(max(n - 1, 1), 4)`` uint32 texels.

    Texel ``i``: words 0-2 are R, G, B, each ``code_i | code_{i+1} << 16`` (two's complement 16-bit codes),
    word 3 the float32 bits of the interval's scale ``max |channel| / PACKED_CODE_MAX`` over both entries
    (0 for a black interval). A one-entry table (a placeholder) becomes one interval with equal ends.
    """
    table = np.asarray(table, dtype=np.float64).reshape(-1, 3)
    if not np.all(np.isfinite(table)):
        raise ValueError("a packed table needs finite entries")
    ends = (table[:-1], table[1:]) if len(table) > 1 else (table, table)
    largest = np.maximum(np.abs(ends[0]).max(axis=1), np.abs(ends[1]).max(axis=1))
    scale = (largest / PACKED_CODE_MAX).astype(np.float32)
    safe = np.where(scale > 0.0, scale.astype(np.float64), 1.0)[:, None]
    # The scale is stored in float32: codes are rounded against it, so |code| may reach 32767 + 1/2 ulp.
    codes = [np.clip(np.rint(end / safe), -PACKED_CODE_MAX, PACKED_CODE_MAX).astype(np.int64) & 0xFFFF for end in ends]
    texels = np.empty((len(scale), 4), np.uint32)
    texels[:, :3] = (codes[0] | (codes[1] << 16)).astype(np.uint32)
    texels[:, 3] = scale.view(np.uint32)
    return texels


def unpack_table_intervals(texels: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The entries a packed table holds: ``(start, end)`` of each interval, ``(m, 3)`` float64 each."""
    texels = np.asarray(texels, dtype=np.uint32)
    scale = texels[:, 3].view(np.float32).astype(np.float64)[:, None]
    words = texels[:, :3].astype(np.int64)
    low, high = words & 0xFFFF, words >> 16
    signed = [np.where(c >= 0x8000, c - 0x10000, c) for c in (low, high)]
    return signed[0] * scale, signed[1] * scale


def packed_tabulated_rgb(texels: np.ndarray, cos_theta) -> np.ndarray:
    """
    The tabulated lookup of a packed table at ``cos_theta`` (clamped to [0, 1]), as the GLSL twin does it:
    interval ``i = min(floor(x), m - 1)`` of ``m``, ``x = cos theta * m``, its two ends mixed linearly.
    """
    start, end = unpack_table_intervals(texels)
    intervals = len(start)
    x = np.clip(np.asarray(cos_theta, dtype=np.float64), 0.0, 1.0) * intervals
    i = np.minimum(x.astype(np.int64), intervals - 1)
    t = (x - i)[..., None]
    return start[i] + t * (end[i] - start[i])
