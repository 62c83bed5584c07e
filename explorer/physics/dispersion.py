"""
Dispersive, absorbing media: the complex index ``n(lambda) + i k(lambda)`` of a named material.

A layer's index parameter may name one of these instead of a number (``n2=chitin``). The shipped
library is :data:`LIBRARY`; a user's own medium is a file named by its path: a CSV of
``wavelength_nm,n,k`` rows (interpolated linearly), or a TOML file of Cauchy or Sellmeier coefficients
(:func:`load_dispersion`). Every entry covers 360-830 nm (:data:`RANGE_NM`), the range of the spectra
and of the colour-matching functions. ``k > 0`` absorbs: waves go as ``exp(+i k_z z)`` (the ``tmm``
convention of :mod:`explorer.physics.fresnel`), so the complex index is ``n + i k``.

Formulas (``lambda`` in nm unless a TOML file says ``unit = "um"``):

- Cauchy: ``n = A + B / lambda^2 + C / lambda^4``; ``k = k0 + a exp(-lambda / b)`` (Stavenga et al. 2015).
- Sellmeier: ``n^2 = A + sum_i B_i lambda^2 / (lambda^2 - C_i)``; ``k = k0``.

References
----------
Leertouwer, Wilts, Stavenga (2011), Opt. Express 19:24061 (chitin, keratin).
Stavenga, Leertouwer, Osorio, Wilts (2015), Light Sci. Appl. 4:e243 (melanin, n and k).
Malitson (1965), J. Opt. Soc. Am. 55:1205 (fused silica). DeVore (1951), J. Opt. Soc. Am. 41:416 (rutile TiO2).
Daimon, Masumura (2007), Appl. Opt. 46:3811 (water, 20 C). Land (1972), Prog. Biophys. 24:75 (guanine).
"""

from __future__ import annotations

import csv
import math
import os
import re
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np
from numpy.typing import ArrayLike

from explorer.errors import LocatedError

#: The wavelengths every medium covers (nm): the spectra's and the CMFs' range.
RANGE_NM = (360.0, 830.0)
#: Suffixes of a user's dispersion file.
FILE_SUFFIXES = (".csv", ".toml")


class DispersionError(LocatedError):
    """A dispersion file or name is wrong (one line naming the file and, where known, the line)."""


@dataclass(frozen=True)
class Dispersion:
    """
    A medium's complex index over wavelength.

    Parameters
    ----------
    name : str
        The library's name, or the file's path for a user's medium.
    formula : str
        The formula with its coefficients, for ``info --dispersions``.
    citation : str
        Where the formula comes from.
    function : callable
        ``wavelength_nm -> n + i k`` (complex ndarray), vectorised.
    step_nm : float or None
        A tabulated medium's wavelength step (the spectra include it); None for a formula.
    """

    name: str
    formula: str
    citation: str
    function: Callable[[np.ndarray], np.ndarray] = field(compare=False, repr=False)
    step_nm: float | None = None

    def index(self, wavelength_nm: ArrayLike) -> np.ndarray:
        """The complex index ``n + i k`` at ``wavelength_nm`` (complex ndarray of its shape)."""
        return np.asarray(self.function(np.asarray(wavelength_nm, dtype=np.float64)), dtype=np.complex128)

    @property
    def absorbing(self) -> bool:
        """Whether ``k > 0`` anywhere in :data:`RANGE_NM` (sampled every nm)."""
        return bool(np.any(self.index(np.arange(RANGE_NM[0], RANGE_NM[1] + 1.0)).imag > 0.0))

    def lowest_real(self) -> tuple[float, float]:
        """``(n, wavelength)``: the smallest ``n`` in :data:`RANGE_NM` (sampled every nm) and where it is."""
        wavelength = np.arange(RANGE_NM[0], RANGE_NM[1] + 1.0)
        n = self.index(wavelength).real
        at = int(np.argmin(n))
        return float(n[at]), float(wavelength[at])

    def real_at(self, wavelength_nm: float) -> float:
        """``n`` at one wavelength (a number for a slider's position or a landmark)."""
        return float(self.index(wavelength_nm).real)


def cauchy(A: float, B: float = 0.0, C: float = 0.0, k0: float = 0.0, a: float = 0.0, b: float = 1.0,
           scale: float = 1.0) -> Callable[[np.ndarray], np.ndarray]:
    """``n = A + B/l^2 + C/l^4``, ``k = k0 + a exp(-l/b)`` with ``l = lambda_nm * scale``."""
    def function(wavelength_nm: np.ndarray) -> np.ndarray:
        lam = wavelength_nm * scale
        return (A + B / lam**2 + C / lam**4) + 1j * (k0 + a * np.exp(-lam / b))
    return function


def sellmeier(A: float, terms: tuple[tuple[float, float], ...], k0: float = 0.0,
              scale: float = 1.0) -> Callable[[np.ndarray], np.ndarray]:
    """``n^2 = A + sum B_i l^2 / (l^2 - C_i)``, ``k = k0`` with ``l = lambda_nm * scale``."""
    def function(wavelength_nm: np.ndarray) -> np.ndarray:
        lam2 = (wavelength_nm * scale) ** 2
        n2 = A + sum(B * lam2 / (lam2 - C) for B, C in terms)
        return np.sqrt(n2) + 1j * k0 * np.ones_like(lam2)
    return function


def _constant(n: float) -> Callable[[np.ndarray], np.ndarray]:
    return lambda wavelength_nm: np.full(np.shape(wavelength_nm), n, dtype=np.complex128)


_UM = 1e-3  # nm -> um: the Sellmeier coefficients below are in um^2, as their papers give them

#: The shipped media, by name.
LIBRARY: dict[str, Dispersion] = {d.name: d for d in (
    Dispersion("air", "n = 1, k = 0", "vacuum; air's 1.0003 is below every tolerance here", _constant(1.0)),
    Dispersion("chitin", "Cauchy: n = 1.517 + 8.80e3 / lambda^2 (nm), k = 0",
               "Leertouwer, Wilts, Stavenga (2011), Opt. Express 19:24061 (butterfly wing scales)", cauchy(1.517, 8.80e3)),
    Dispersion("keratin", "Cauchy: n = 1.532 + 5.89e3 / lambda^2 (nm), k = 0",
               "Leertouwer, Wilts, Stavenga (2011), Opt. Express 19:24061 (bird feather barbules)", cauchy(1.532, 5.89e3)),
    Dispersion("melanin", "Cauchy: n = 1.648 + 2.37e4 / lambda^2 (nm), k = 0.56 exp(-lambda / 270 nm)",
               "Stavenga, Leertouwer, Osorio, Wilts (2015), Light Sci. Appl. 4:e243 (eumelanin of bird-of-paradise barbules)",
               cauchy(1.648, 2.37e4, a=0.56, b=270.0)),
    Dispersion("guanine", "n = 1.83, k = 0 (no dispersion measured)",
               "Land (1972), Prog. Biophys. Mol. Biol. 24:75 (guanine crystal platelets of fish and spiders)", _constant(1.83)),
    Dispersion("water", "Sellmeier (um): n^2 = 1 + 0.5684028 l^2/(l^2 - 5.101830e-3) + 0.1726177 l^2/(l^2 - 1.821154e-2)"
               " + 2.086190e-2 l^2/(l^2 - 2.620722e-2) + 0.1130749 l^2/(l^2 - 10.69793), k = 0",
               "Daimon, Masumura (2007), Appl. Opt. 46:3811 (20 C)",
               sellmeier(1.0, ((5.684027565e-1, 5.101829712e-3), (1.726177391e-1, 1.821153936e-2),
                               (2.086189578e-2, 2.620722293e-2), (1.130748688e-1, 1.069792721e1)), scale=_UM)),
    Dispersion("SiO2", "Sellmeier (um): n^2 = 1 + 0.6961663 l^2/(l^2 - 0.0684043^2) + 0.4079426 l^2/(l^2 - 0.1162414^2)"
               " + 0.8974794 l^2/(l^2 - 9.896161^2), k = 0",
               "Malitson (1965), J. Opt. Soc. Am. 55:1205 (fused silica)",
               sellmeier(1.0, ((0.6961663, 0.0684043**2), (0.4079426, 0.1162414**2), (0.8974794, 9.896161**2)), scale=_UM)),
    Dispersion("TiO2", "Sellmeier (um): n^2 = 5.913 + 0.2441 / (l^2 - 0.0803), k = 0 (rutile, ordinary ray)",
               "DeVore (1951), J. Opt. Soc. Am. 41:416",
               # DeVore's form A + B/(l^2 - C) is a Sellmeier term with B_i = B/C: B l^2/(C(l^2 - C)) = B/(l^2 - C) + B/C.
               sellmeier(5.913 - 0.2441 / 0.0803, ((0.2441 / 0.0803, 0.0803),), scale=_UM)),
)}


def is_dispersion_text(text: str) -> bool:
    """Whether ``text`` (a parameter's value) names a medium rather than giving a number."""
    try:
        float(text)
    except (TypeError, ValueError):
        return True
    return False


def names() -> list[str]:
    """The library's names."""
    return list(LIBRARY)


def dispersion_named(text: str, origin: str = "--set", base: Path | None = None) -> Dispersion:
    """
    The medium ``text`` names: a library entry (case-insensitive), or a ``.csv``/``.toml`` file (relative
    to ``base``, default the working folder). Anything else is a one-line :class:`DispersionError` at
    ``origin`` listing the library.
    """
    text = str(text).strip()
    for name, entry in LIBRARY.items():
        if name.lower() == text.lower():
            return entry
    if Path(text).suffix.lower() in FILE_SUFFIXES:
        path = Path(text) if base is None or Path(text).is_absolute() else base / text
        return load_dispersion(path)
    raise DispersionError(origin, None, f"{text!r} is neither a number nor a dispersion: one of {', '.join(LIBRARY)}, "
                                        f"or a file ending in {' or '.join(FILE_SUFFIXES)}")


def _covers(where: str, line: int | None, low: float, high: float) -> None:
    if low > RANGE_NM[0] or high < RANGE_NM[1]:
        raise DispersionError(where, line, f"covers {low:g}-{high:g} nm; a dispersion needs {RANGE_NM[0]:g}-{RANGE_NM[1]:g} nm")


def load_dispersion(path: str | os.PathLike[str]) -> Dispersion:
    """A user's medium from a ``.csv`` (``wavelength_nm,n,k``) or ``.toml`` (Cauchy or Sellmeier) file."""
    path = Path(path)
    where = str(path)
    if path.suffix.lower() not in FILE_SUFFIXES:
        raise DispersionError(where, None, f"a dispersion file ends in {' or '.join(FILE_SUFFIXES)}")
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise DispersionError(where, None, "no such file") from None
    except (OSError, UnicodeDecodeError) as error:
        raise DispersionError(where, None, f"cannot be read ({type(error).__name__})") from None
    return _load_csv(where, text) if path.suffix.lower() == ".csv" else _load_toml(where, text)


def _load_csv(where: str, text: str) -> Dispersion:
    """``wavelength_nm,n,k`` rows, an optional header line, ``#`` comments; wavelengths increasing."""
    rows: list[tuple[float, float, float]] = []
    lines: list[int] = []
    for number, row in enumerate(csv.reader(text.splitlines()), start=1):
        cells = [c.strip() for c in row]
        if not cells or not any(cells) or cells[0].startswith("#"):
            continue
        if not rows and not lines and not _numeric(cells[0]):
            if [c.lower() for c in cells[:3]] != ["wavelength_nm", "n", "k"]:
                raise DispersionError(where, number, f"the header must be wavelength_nm,n,k (got {','.join(cells)[:60]!r})")
            lines.append(0)  # the header is read
            continue
        if len(cells) != 3 or not all(_numeric(c) for c in cells):
            raise DispersionError(where, number, f"expected three numbers wavelength_nm,n,k (got {','.join(cells)[:60]!r})")
        lam, n, k = (float(c) for c in cells)
        if not (math.isfinite(lam) and math.isfinite(n) and math.isfinite(k)) or lam <= 0.0 or n <= 0.0 or k < 0.0:
            raise DispersionError(where, number, "needs a wavelength > 0, n > 0 and k >= 0, all finite")
        if rows and lam <= rows[-1][0]:
            raise DispersionError(where, number, f"wavelengths must increase ({lam:g} after {rows[-1][0]:g})")
        rows.append((lam, n, k))
        lines.append(number)
    if len(rows) < 2:
        raise DispersionError(where, None, "needs at least two rows wavelength_nm,n,k")
    table = np.array(rows)
    _covers(where, None, table[0, 0], table[-1, 0])
    steps = np.diff(table[:, 0])
    step = float(np.min(steps))

    def function(wavelength_nm: np.ndarray) -> np.ndarray:
        return np.interp(wavelength_nm, table[:, 0], table[:, 1]) + 1j * np.interp(wavelength_nm, table[:, 0], table[:, 2])

    return Dispersion(where, f"table of {len(rows)} rows, {table[0, 0]:g}-{table[-1, 0]:g} nm, interpolated linearly",
                      f"the file {where}", function, step_nm=step)


def _numeric(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


_TOML_LINE = re.compile(r"\(at line (\d+), column \d+\)")
_TOML_KEYS = {"formula", "unit", "citation", "A", "B", "C", "k0", "a", "b", "terms"}


def _key_line(text: str, key: str) -> int | None:
    for number, line in enumerate(text.splitlines(), start=1):
        if re.match(rf"\s*{re.escape(key)}\s*=", line):
            return number
    return None


def _load_toml(where: str, text: str) -> Dispersion:
    """
    ``formula = "cauchy"`` with ``A``, ``B``, ``C`` and ``k0``, ``a``, ``b``; or ``formula = "sellmeier"`` with
    ``A`` (default 1), ``terms = [[B1, C1], ...]`` and ``k0``. ``unit = "nm"`` (default) or ``"um"`` for the
    wavelength in the formula; ``citation = "..."`` optional.
    """
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as error:
        found = _TOML_LINE.search(str(error))
        raise DispersionError(where, int(found.group(1)) if found else None,
                              "not valid TOML: " + _TOML_LINE.sub("", str(error)).strip()) from None
    unknown = sorted(set(data) - _TOML_KEYS)
    if unknown:
        raise DispersionError(where, _key_line(text, unknown[0]), f"unknown key {unknown[0]!r} (keys: {', '.join(sorted(_TOML_KEYS))})")
    formula = data.get("formula")
    if formula not in ("cauchy", "sellmeier"):
        raise DispersionError(where, _key_line(text, "formula"), 'needs formula = "cauchy" or "sellmeier"')
    unit = data.get("unit", "nm")
    if unit not in ("nm", "um"):
        raise DispersionError(where, _key_line(text, "unit"), 'unit must be "nm" or "um"')
    scale = 1.0 if unit == "nm" else _UM

    def number(key: str, default: float | None) -> float:
        value = data.get(key, default)
        if value is None:
            raise DispersionError(where, None, f"a {formula} formula needs {key} = NUMBER")
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            raise DispersionError(where, _key_line(text, key), f"{key} must be a finite number")
        return float(value)

    k0 = number("k0", 0.0)
    if formula == "cauchy":
        A, B, C, a, b = number("A", None), number("B", 0.0), number("C", 0.0), number("a", 0.0), number("b", 1.0)
        if b <= 0.0 or a < 0.0:
            raise DispersionError(where, _key_line(text, "b" if b <= 0.0 else "a"), "k = k0 + a exp(-lambda/b) needs a >= 0 and b > 0")
        function = cauchy(A, B, C, k0, a, b, scale)
        shown = f"Cauchy ({unit}): n = {A:g} + {B:g}/l^2 + {C:g}/l^4, k = {k0:g} + {a:g} exp(-l/{b:g})"
        if "terms" in data:
            raise DispersionError(where, _key_line(text, "terms"), "terms belongs to a sellmeier formula")
    else:
        A = number("A", 1.0)
        terms = data.get("terms")
        line = _key_line(text, "terms")
        if not isinstance(terms, list) or not terms or not all(
                isinstance(t, list) and len(t) == 2 and all(isinstance(x, (int, float)) and not isinstance(x, bool)
                                                            and math.isfinite(x) for x in t) for t in terms):
            raise DispersionError(where, line, "a sellmeier formula needs terms = [[B1, C1], [B2, C2], ...] (numbers)")
        for key in ("B", "C", "a", "b"):
            if key in data:
                raise DispersionError(where, _key_line(text, key), f"{key} belongs to a cauchy formula")
        function = sellmeier(A, tuple((float(B), float(C)) for B, C in terms), k0, scale)
        shown = f"Sellmeier ({unit}): n^2 = {A:g}" + "".join(f" + {B:g} l^2/(l^2 - {C:g})" for B, C in terms) + f", k = {k0:g}"
    if k0 < 0.0:
        raise DispersionError(where, _key_line(text, "k0"), "k0 must be >= 0")
    grid = np.arange(RANGE_NM[0], RANGE_NM[1] + 1.0)
    with np.errstate(all="ignore"):
        values = function(grid)
    if not np.all(np.isfinite(values)) or np.any(values.real <= 0.0) or np.any(values.imag < 0.0):
        bad = float(grid[np.argmax(~np.isfinite(values) | (values.real <= 0.0) | (values.imag < 0.0))])
        raise DispersionError(where, _key_line(text, "formula"),
                              f"gives no valid index (n > 0, k >= 0, finite) at {bad:g} nm, inside {RANGE_NM[0]:g}-{RANGE_NM[1]:g} nm")
    citation = data.get("citation", f"the file {where}")
    return Dispersion(where, shown, str(citation), function)


def complex_index(value: float | Dispersion, k: float, wavelength_nm: ArrayLike) -> np.ndarray:
    """
    A layer's complex index at ``wavelength_nm``: ``value`` (a number, or a medium's ``n + i k``) plus
    ``i k`` (an extinction parameter adds to a medium's own).
    """
    wavelength_nm = np.asarray(wavelength_nm, dtype=np.float64)
    base = value.index(wavelength_nm) if isinstance(value, Dispersion) else np.full(wavelength_nm.shape, float(value), np.complex128)
    return base + 1j * float(k)


def describe(value: float | Dispersion) -> str:
    """A number as ``1.5``, a medium by its name."""
    return value.name if isinstance(value, Dispersion) else f"{float(value):g}"
