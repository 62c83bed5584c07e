"""
MERL ``.binary`` files: measured isotropic BRDFs (Matusik et al. 2003), read into a material whose shader
looks the table up (``shaders/lib/merl.glsl``) and whose numpy twin looks up the same float32 table
(:class:`MerlModel`, :mod:`explorer.physics.merl`).

The file: three little-endian int32, the bins in ``theta_h``, ``theta_d`` and ``phi_d`` (90, 90, 180),
then ``3 x 90 x 90 x 180`` little-endian float64, the red, green then blue blocks, each in C order
``(theta_h, theta_d, phi_d)``. A value times its channel's scale (:data:`explorer.physics.merl.CHANNEL_SCALES`)
is the BRDF in 1/sr; MERL marks the bins it did not measure (below the horizon) with negative values,
read here as 0 (no light), as MERL's renderers do.

:func:`write_merl` writes a table in that format (from :func:`tabulate`, an analytic BRDF at the bins'
middles): the tests' MERL files, since MERL's own data cannot be shipped.

This module never imports :mod:`explorer.materials.brd` (which reads these files through it).

References
----------
Matusik, Pfister, Brand, McMillan (2003). A Data-Driven Reflectance Model. ACM TOG 22(3); MERL's
``BRDFRead.cpp``.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Callable

import numpy as np

from explorer.errors import LocatedError
from explorer.physics.merl import (
    CHANNEL_SCALES, PHI_D_BINS, THETA_D_BINS, THETA_H_BINS, merl_bin_centres, merl_directions, merl_lookup,
)

#: The suffix of MERL's files.
SUFFIX = ".binary"
#: Values per channel, and the whole file's size in bytes (header + 3 channels of float64).
BINS = THETA_H_BINS * THETA_D_BINS * PHI_D_BINS
HEADER_BYTES = 12
FILE_BYTES = HEADER_BYTES + 3 * BINS * 8
#: What a material argument may be, for messages about files that are none of these.
SUPPORTED = "supported: .brd and BRDF Explorer .brdf text files ('analytic'), MERL isotropic .binary tables (90x90x180)"

#: The material's shader section (the Material that :func:`explorer.materials.brd.load_material` builds).
SHADER = '#include "lib/merl.glsl"\nvec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y) { return merl_brdf(L, V, N, X, Y); }\n'
#: Its ``# model:`` name.
MODEL = "merl"


class MerlFileError(LocatedError):
    """A ``.binary`` file that is not a MERL isotropic table, or binary data that is no material at all."""


def looks_binary(data: bytes) -> bool:
    """Whether ``data`` is binary, not text: a NUL byte in its first 4 KiB (no material file has one)."""
    return b"\0" in data[:4096]


def header_dimensions(data: bytes) -> tuple[int, int, int] | None:
    """The three int32 of a MERL header, or None when ``data`` is shorter than one."""
    if len(data) < HEADER_BYTES:
        return None
    return tuple(int(v) for v in np.frombuffer(data[:HEADER_BYTES], dtype="<i4"))


def is_merl(data: bytes) -> bool:
    """Whether ``data`` is a whole MERL isotropic table: its header 90 90 180 and its size 12 + 3 x 1458000 x 8 bytes."""
    return header_dimensions(data) == (THETA_H_BINS, THETA_D_BINS, PHI_D_BINS) and len(data) == FILE_BYTES


def not_a_material(name: str, data: bytes) -> MerlFileError:
    """The one-line error of a binary file that is no material (what it is, what is supported)."""
    return MerlFileError(name, None, f"binary data ({len(data)} bytes), not a material file; {SUPPORTED}")


class MerlTable:
    """
    A MERL table, ``rgb`` ``(90, 90, 180, 3)`` float32 linear RGB (1/sr, the channel scales applied, the
    unmeasured bins 0): what the shader's texture and the numpy twin both hold.
    """

    def __init__(self, rgb, name: str = "<array>"):
        rgb = np.asarray(rgb, dtype=np.float32)
        if rgb.shape != (THETA_H_BINS, THETA_D_BINS, PHI_D_BINS, 3):
            raise MerlFileError(name, None, f"a MERL table is (90, 90, 180, 3), got {rgb.shape}")
        rgb.setflags(write=False)
        self.rgb = rgb
        self.name = name

    @classmethod
    def from_bytes(cls, data: bytes, name: str) -> "MerlTable":
        """Parse a file's bytes; :class:`MerlFileError` (one line: what was found, what is expected) otherwise."""
        dimensions = header_dimensions(data)
        expected = (THETA_H_BINS, THETA_D_BINS, PHI_D_BINS)
        what = f"a MERL isotropic BRDF is a header of three int32 {expected[0]} {expected[1]} {expected[2]} then 3 x {BINS} float64 ({FILE_BYTES} bytes)"
        if dimensions is None:
            raise MerlFileError(name, None, f"not a MERL .binary file: {len(data)} bytes, no header; {what}")
        if dimensions != expected:
            found = " ".join(str(d) for d in dimensions)
            raise MerlFileError(name, None, f"not a MERL isotropic .binary file: header {found}; {what}")
        if len(data) != FILE_BYTES:
            raise MerlFileError(name, None, f"truncated or padded MERL .binary file: {len(data)} bytes; {what}")
        raw = np.frombuffer(data, dtype="<f8", offset=HEADER_BYTES).reshape(3, THETA_H_BINS, THETA_D_BINS, PHI_D_BINS)
        if not np.isfinite(raw).all():
            raise MerlFileError(name, None, f"MERL .binary file holds {int((~np.isfinite(raw)).sum())} NaN or infinite values")
        # MERL's negative values mark unmeasured bins (below the horizon): no light, as its renderers read them.
        rgb = np.moveaxis(np.maximum(raw, 0.0), 0, -1) * CHANNEL_SCALES
        return cls(rgb, name)

    @classmethod
    def load(cls, path: str | os.PathLike[str]) -> "MerlTable":
        name = os.fspath(path)
        try:
            data = Path(path).read_bytes()
        except OSError as error:
            raise MerlFileError(name, None, f"cannot read MERL file: {error.strerror or error}") from None
        return cls.from_bytes(data, name)

    def texture(self) -> np.ndarray:
        """The shader's ``merl_table``: ``(8100, 180, 3)``, row ``i_h 90 + i_d``, column ``i_phi``."""
        return self.rgb.reshape(THETA_H_BINS * THETA_D_BINS, PHI_D_BINS, 3)

    def twin(self, values=None) -> "MerlModel":
        """The numpy twin of the material (it has no parameters: ``values`` are ignored)."""
        return MerlModel(self)


class MerlModel:
    """
    Twin of a MERL material's shader (``merl_brdf`` of ``shaders/lib/merl.glsl``): the nearest bin of the
    same float32 table, in the frame (X, Y, N).
    """

    name = MODEL
    #: A measured BRDF is no Dirac: the env view integrates it.
    mirror_reflection = None
    mirror_only = False

    def __init__(self, table: MerlTable):
        self.table = table

    def brdf(self, L, V, N, X, Y) -> np.ndarray:
        """The BRDF for unit vectors ``(..., 3)`` (world ``L``, ``V`` and the frame ``X``, ``Y``, ``N``)."""
        X, Y, N = (np.asarray(a, dtype=np.float64) for a in (X, Y, N))

        def local(d):
            d = np.asarray(d, dtype=np.float64)
            return np.stack([np.sum(d * X, axis=-1), np.sum(d * Y, axis=-1), np.sum(d * N, axis=-1)], axis=-1)

        return merl_lookup(self.table.rgb, local(L), local(V))

    def textures(self) -> dict[str, np.ndarray]:
        return {"merl_table": self.table.texture()}


def tabulate(brdf: Callable[[np.ndarray, np.ndarray], np.ndarray]) -> np.ndarray:
    """
    An analytic BRDF at the middle of every MERL bin: ``brdf(L, V) -> (..., 3)`` (local unit vectors,
    normal ``+z``) at :func:`explorer.physics.merl.merl_bin_centres`, ``phi_h = 0``; ``(90, 90, 180, 3)`` float64.
    """
    theta_h, theta_d, phi_d = merl_bin_centres()
    L, V = merl_directions(theta_h[:, None, None], theta_d[None, :, None], phi_d[None, None, :])
    values = np.asarray(brdf(L, V), dtype=np.float64)
    return np.broadcast_to(values, (THETA_H_BINS, THETA_D_BINS, PHI_D_BINS, 3))


def write_merl(path: str | os.PathLike[str], rgb) -> Path:
    """
    Write a ``(90, 90, 180, 3)`` table of linear RGB BRDF values (1/sr) as a MERL ``.binary`` file: each
    channel divided by its scale, so that reading it back gives ``rgb`` (to float64 rounding).
    """
    rgb = np.asarray(rgb, dtype=np.float64)
    if rgb.shape != (THETA_H_BINS, THETA_D_BINS, PHI_D_BINS, 3):
        raise ValueError(f"a MERL table is (90, 90, 180, 3), got {rgb.shape}")
    from explorer.files import atomic_output

    path = Path(path)
    raw = np.moveaxis(rgb / CHANNEL_SCALES, -1, 0)
    with atomic_output(path) as temporary:
        with open(temporary, "wb") as stream:
            stream.write(np.array([THETA_H_BINS, THETA_D_BINS, PHI_D_BINS], dtype="<i4").tobytes())
            stream.write(np.ascontiguousarray(raw, dtype="<f8").tobytes())
    return path
