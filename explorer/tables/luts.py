"""
Precomputed tables in ``luts/``, generated from colour-science, with a manifest.

Each table is a ``.npy`` file listed in ``luts/manifest.json`` with its source, range, resolution,
the parameters that generated it and a SHA-256 checksum. :func:`load` regenerates a table that is
missing, altered, or generated with other parameters than the code's: a stale table is never used.
The shipped tables (:data:`LUT_DIR`, see :mod:`explorer.resources`) are read-only: a stale one is
regenerated into the user cache (``~/.cache/bragg-explorer/luts``) and read from there afterwards.

Run ``python -m explorer.tables.luts`` in a source checkout to regenerate the committed tables.

Tables
------
cmf_1nm
    The CIE 1931 2° CMFs at every nm from 360 to 830, normalised so that ``sum(ybar) == 1`` (the
    spectral reference integrates against them).
cmf_cumulative
    The cumulative integrals ``C(lambda)`` of those CMFs (Eq. 16 of Fourneau et al. 2024), at the
    472 bin edges ``359.5 + k`` nm: the CMFs are constant over each 1 nm bin, so ``C`` is exactly
    piecewise linear between nodes and a box spectrum integrates to ``C(hi) - C(lo)`` (Eq. 15).
sensitivity_fourier
    The Fourier transform ``S^_j(mu)`` of the linear sRGB sensitivities ``s_j`` of the colour
    convention, as functions of ``nu = 1/lambda`` (Belcour & Barla 2017, Eqs. 7-8):
    ``S^_j(mu) = sum_lambda s_j(lambda) exp(-2 pi i mu / lambda)`` over the 471 nodes of the spectral
    reference, with ``s_j = (M cmf)_j`` and ``M`` the XYZ -> RGB matrix, so ``S^_j(0) = 1`` (white).
    Being the transform of the very sum the 1 nm reference computes, Eq. 10 with it converges to that
    reference as ``m`` grows. Sampled at OPDs ``mu = 10 k`` nm, ``k = 0..4095``, and stored
    demodulated, ``E_j(mu) = S^_j(mu) exp(+2 pi i mu / carrier_j)``, with each channel's carrier near
    its centroid in ``nu``: the envelope ``E_j`` is smooth, so linear interpolation between nodes is
    within 6e-5 of the transform (2.5e-3 without demodulation). Shape ``(2, 4096, 3)``: real parts,
    imaginary parts (the paper's N x 2 three-channel texture, Section 5); zero beyond the last node.
lobes_fgd_correction, lobes_ggx_moments
    Belcour's (2018) FGD term for :mod:`explorer.physics.lobes`: a rough dielectric interface's directional
    albedo minus the Fresnel term (unpolarised), over (eta, alpha, cos theta); and the GGX reflection
    lobe's albedo and mean half-angle cosine over (alpha, cos theta), for rough conductors.
"""

from __future__ import annotations

import contextlib
import hashlib
import io
import json
import os
import sys
from pathlib import Path
from typing import Callable

import numpy as np

from explorer.physics import colorimetry
from explorer import resources
from explorer.files import OutputError, write_bytes_atomic, write_text_atomic

#: The shipped tables (read-only: see :func:`load`).
LUT_DIR = resources.LUT_DIR
MANIFEST = "manifest.json"
#: Bump when a generator changes what it writes.
GENERATOR_VERSION = 1

#: First node of ``cmf_cumulative`` (nm) and its spacing.
CUMULATIVE_START = colorimetry.WAVELENGTH_MIN - 0.5
CUMULATIVE_STEP = 1.0


def _generate_cmf_1nm() -> np.ndarray:
    return colorimetry.colour_matching_functions().astype(np.float64)


def _generate_cmf_cumulative() -> np.ndarray:
    cmf = colorimetry.colour_matching_functions()
    return np.concatenate([np.zeros((1, 3)), np.cumsum(cmf, axis=0)]).astype(np.float64)


#: The ``sensitivity_fourier`` table: OPD step (nm), node count, and the carrier wavelengths (nm) of
#: the R, G, B channels (their sensitivities' centroids in ``nu``, 653.2, 545.7 and 440.6 nm, rounded).
SENSITIVITY_FOURIER_STEP = 10.0
SENSITIVITY_FOURIER_COUNT = 4096
SENSITIVITY_FOURIER_CARRIER_NM = (653.0, 546.0, 441.0)


def _generate_sensitivity_fourier() -> np.ndarray:
    # Element-wise products and numpy's pairwise sums, not BLAS: the same bits on every machine.
    cmf, matrix = colorimetry.colour_matching_functions(), colorimetry.xyz_to_rgb_matrix()
    sensitivities = (cmf[:, None, :] * matrix[None, :, :]).sum(axis=-1)
    mu = np.arange(SENSITIVITY_FOURIER_COUNT, dtype=np.float64) * SENSITIVITY_FOURIER_STEP
    nu = 1.0 / colorimetry.WAVELENGTHS
    envelope = np.empty((mu.size, 3), dtype=np.complex128)
    for j, carrier in enumerate(SENSITIVITY_FOURIER_CARRIER_NM):
        # exp(-2 pi i mu nu) exp(+2 pi i mu / carrier), in one phase: no large phases cancel.
        phase = np.exp(-2j * np.pi * mu[:, None] * (nu - 1.0 / carrier)[None, :])
        envelope[:, j] = (phase * sensitivities[None, :, j]).sum(axis=-1)
    return np.stack([envelope.real, envelope.imag]).astype(np.float64)


def _generate_lobes_fgd_correction() -> np.ndarray:
    from explorer.physics.lobes_fgd import generate_fgd_correction  # the physics lives in explorer.physics.lobes_fgd

    return generate_fgd_correction()


def _generate_lobes_ggx_moments() -> np.ndarray:
    from explorer.physics.lobes_fgd import generate_ggx_moments

    return generate_ggx_moments()


def _source() -> str:
    import colour

    return f"colour-science {colour.__version__}: colour.MSDS_CMFS['{colorimetry.CMFS_NAME}']"


TABLES: dict[str, dict] = {
    "cmf_1nm": {
        "generate": _generate_cmf_1nm,
        "spec": {
            "quantity": "CIE 1931 2 degree CMFs, normalised so that sum(ybar) = 1",
            "range_nm": [colorimetry.WAVELENGTH_MIN, colorimetry.WAVELENGTH_MAX],
            "resolution_nm": 1.0,
            "shape": [471, 3],
        },
    },
    "cmf_cumulative": {
        "generate": _generate_cmf_cumulative,
        "spec": {
            "quantity": "cumulative integral of the normalised CMFs (Eq. 16), at 1 nm bin edges",
            "range_nm": [CUMULATIVE_START, colorimetry.WAVELENGTH_MAX + 0.5],
            "resolution_nm": CUMULATIVE_STEP,
            "shape": [472, 3],
        },
    },
    "lobes_fgd_correction": {
        "generate": _generate_lobes_fgd_correction,
        "spec": {
            "quantity": "FGD - Fresnel (unpolarised) of a rough GGX dielectric interface, eta x alpha x cos theta "
            "(explorer.physics.lobes; Belcour 2018's FGD term)",
            "eta": "4 ** linspace(-1, 1, 33)", "alpha": "linspace(0, 1, 16)",
            "cos_theta": "t = linspace(0, 1, 33) of explorer.physics.lobes.fgd_cos_coordinate (critical angle at t = 1/2 for eta < 1)",
            "quadrature": "48 x 48 midpoints of the GGX normal distribution",
            "resolution_nm": None,  # no wavelength axis
            "shape": [33, 16, 33],
        },
    },
    "lobes_ggx_moments": {
        "generate": _generate_lobes_ggx_moments,
        "spec": {
            "quantity": "GGX reflection lobe albedo (F = 1) and mean half-angle cosine, [E, cbar_d] x alpha x cos theta "
            "(explorer.physics.lobes: conductors' FGD ~ E F(cbar_d))",
            "alpha": "linspace(0, 1, 16)", "cos_theta": "linspace(0, 1, 33)",
            "quadrature": "48 x 48 midpoints of the GGX normal distribution",
            "resolution_nm": None,  # no wavelength axis
            "shape": [2, 16, 33],
        },
    },
    "sensitivity_fourier": {
        "generate": _generate_sensitivity_fourier,
        "spec": {
            "quantity": "Fourier transform over nu = 1/lambda of the linear sRGB sensitivities (Belcour & "
            "Barla 2017, Eqs. 7-8), demodulated by exp(+2 pi i mu / carrier); [real, imag]",
            "range_nm": [0.0, SENSITIVITY_FOURIER_STEP * (SENSITIVITY_FOURIER_COUNT - 1)],
            "resolution_nm": SENSITIVITY_FOURIER_STEP,
            "carrier_nm": list(SENSITIVITY_FOURIER_CARRIER_NM),
            "shape": [2, SENSITIVITY_FOURIER_COUNT, 3],
        },
    },
}


def _sha256(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def _read_manifest(directory: Path) -> dict:
    """The manifest's ``{"tables": {name: entry}}``; an unreadable or malformed one reads as empty (regenerate)."""
    try:
        manifest = json.loads((directory / MANIFEST).read_text(encoding="utf-8"))
    except (OSError, ValueError, RecursionError):
        return {"tables": {}}
    if not isinstance(manifest, dict) or not isinstance(manifest.get("tables"), dict):
        return {"tables": {}}
    manifest["tables"] = {k: v for k, v in manifest["tables"].items() if isinstance(v, dict)}
    return manifest


def _read_table(name: str, directory: Path) -> np.ndarray | str:
    """
    Table ``name`` of ``directory`` as its manifest records it, or why not (a string). The file is read once
    and its bytes checked against the manifest's checksum before they are parsed: a table replaced while
    it is read (another process regenerating it, :func:`generate`) is never half-read.
    """
    entry = _read_manifest(directory)["tables"].get(name)
    path = directory / f"{name}.npy"
    if entry is None:
        return "not in the manifest"
    if not path.exists():
        return "file missing"
    if {k: entry.get(k) for k in _expected_spec(name)} != _expected_spec(name):
        return "generated with other parameters"
    try:
        data = path.read_bytes()
    except OSError as error:
        return f"unreadable ({error.strerror or error})"
    if entry.get("sha256") != hashlib.sha256(data).hexdigest():
        return "checksum mismatch"
    try:
        table = np.load(io.BytesIO(data), allow_pickle=False)
    except (ValueError, EOFError, OSError):
        return "not a .npy file"
    if list(table.shape) != list(TABLES[name]["spec"]["shape"]) or table.dtype != np.float64:
        return "not the recorded shape"
    return table


def _expected_spec(name: str) -> dict:
    return {**TABLES[name]["spec"], "generator_version": GENERATOR_VERSION, "dtype": "float64"}


def staleness(name: str, directory: Path = LUT_DIR) -> str | None:
    """Why table ``name`` cannot be used as it is (``None`` when it is up to date)."""
    found = _read_table(name, directory)
    return found if isinstance(found, str) else None


@contextlib.contextmanager
def _manifest_lock(directory: Path):
    """
    An exclusive lock on ``directory`` (the folder itself: no lock file is left) while its manifest is read,
    updated and replaced; POSIX only, none elsewhere.
    """
    try:
        import fcntl
    except ImportError:  # pragma: no cover - not POSIX
        yield
        return
    handle = os.open(directory, os.O_RDONLY)
    try:
        fcntl.flock(handle, fcntl.LOCK_EX)
        yield
    finally:
        os.close(handle)  # releases the lock


def generate(name: str, directory: Path = LUT_DIR) -> np.ndarray:
    """
    Generate table ``name``, write it to ``directory`` and record it in the manifest.

    Both files are written whole to a temporary file and renamed (:func:`explorer.files.atomic_output`):
    a process loading the tables meanwhile reads the old table or the new one, never part of one. The
    manifest's read-modify-write is serialised by a lock, so that concurrent regenerations keep every entry.
    """
    table = np.ascontiguousarray(TABLES[name]["generate"]())
    directory.mkdir(parents=True, exist_ok=True)
    path = directory / f"{name}.npy"
    buffer = io.BytesIO()
    np.save(buffer, table)
    data = buffer.getvalue()
    try:
        write_bytes_atomic(path, data)
        with _manifest_lock(directory):
            manifest = _read_manifest(directory)
            manifest["tables"][name] = {
                "file": path.name,
                "source": _source(),
                **_expected_spec(name),
                "sha256": hashlib.sha256(data).hexdigest(),
            }
            write_text_atomic(directory / MANIFEST, json.dumps(manifest, indent=2, sort_keys=True) + "\n")
    except OutputError as error:
        raise OSError(str(error)) from None  # load() falls back to the table in memory
    return table


_cache: dict[tuple[str, Path], np.ndarray] = {}


def cache_lut_dir() -> Path:
    """Where stale shipped tables are regenerated: ``luts`` in :func:`explorer.resources.cache_dir`."""
    return resources.cache_dir() / "luts"


def load(name: str, directory: Path | None = None, log: Callable[[str], None] | None = None) -> np.ndarray:
    """
    Table ``name``, regenerated first when missing or stale (never silently used stale).

    Parameters
    ----------
    name : str
        A key of :data:`TABLES`.
    directory : Path, optional
        A table folder of one's own, where a stale table is regenerated. By default the shipped tables
        (:data:`LUT_DIR`), never written: a stale one is replaced by the user cache's copy
        (:func:`cache_lut_dir`), regenerated there first unless that copy is current.
    log : callable, optional
        Receives the one-line message of a regeneration (default: stderr).

    Notes
    -----
    When the target folder cannot be written, the regenerated table is used from memory.
    """
    shipped = directory is None
    directory = Path(LUT_DIR if shipped else directory)
    key = (name, directory)
    if key in _cache:
        return _cache[key]
    found = _read_table(name, directory)
    cached = _read_table(name, cache_lut_dir()) if shipped and isinstance(found, str) else None
    if not isinstance(found, str):
        table = found
    elif cached is not None and not isinstance(cached, str):
        table = cached
    else:
        reason = found
        target = cache_lut_dir() if shipped else directory
        where = f" into {target}" if shipped else ""
        (log or (lambda m: print(m, file=sys.stderr)))(f"luts: regenerating {name} ({reason}){where}")
        try:
            table = generate(name, target)
        except OSError:
            table = np.ascontiguousarray(TABLES[name]["generate"]())
    table.setflags(write=False)
    _cache[key] = table
    return table


def cmf_cumulative_at(wavelength) -> np.ndarray:
    """
    ``C(lambda)`` by linear interpolation between the table's nodes, clamped outside them: exactly
    what a linearly filtered, edge-clamped texture of the table returns.

    Returns
    -------
    ndarray, shape ``wavelength.shape + (3,)``
    """
    table = load("cmf_cumulative")
    x = (np.asarray(wavelength, dtype=np.float64) - CUMULATIVE_START) / CUMULATIVE_STEP
    x = np.clip(x, 0.0, table.shape[0] - 1.0)
    i = np.minimum(np.floor(x).astype(np.int64), table.shape[0] - 2)
    f = (x - i)[..., None]
    return table[i] * (1.0 - f) + table[i + 1] * f


def main() -> int:
    resources.require_checkout("python -m explorer.tables.luts")  # an installation regenerates into cache_lut_dir()
    for name in TABLES:
        table = generate(name)
        print(f"luts/{name}.npy  shape {table.shape}  {_sha256(LUT_DIR / f'{name}.npy')[:16]}…")
    print(f"luts/{MANIFEST} written ({_source()})")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
