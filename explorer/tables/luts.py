"""
The table store: precomputed tables in ``luts/``, with a manifest. It knows no physics.

Each table is a ``.npy`` file listed in ``luts/manifest.json`` with its source, range, resolution, the
parameters that generated it and a SHA-256 checksum. The physics module a table belongs to declares it
with :func:`register` (its generator and its spec) when it is imported; :func:`load` returns it,
regenerated first when missing, altered, or generated with other parameters than the code's: a stale
table is never used. The shipped tables (:data:`LUT_DIR`, see :mod:`explorer.resources`) are read-only:
a stale one is regenerated into the user cache (``~/.cache/bragg-explorer/luts``) and read from there
afterwards.

``python -m explorer.dev.regenerate_tables`` (a source checkout) regenerates the committed tables.

Tables, and the modules that register them
------------------------------------------
cmf_1nm, cmf_cumulative
    The CMFs and their cumulative integrals (:mod:`explorer.physics.colorimetry`).
sensitivity_fourier
    The Fourier transform of the sensitivities (:mod:`explorer.physics.thinfilm`).
lobes_fgd_correction, lobes_ggx_moments
    Belcour's FGD term and the GGX lobe's moments (:mod:`explorer.physics.lobes_fgd`).
"""

from __future__ import annotations

import contextlib
import hashlib
import io
import json
import os
import sys
from pathlib import Path
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from explorer import resources
from explorer.files import OutputError, write_bytes_atomic, write_text_atomic

#: The shipped tables (read-only: see :func:`load`).
LUT_DIR = resources.LUT_DIR
MANIFEST = "manifest.json"
#: Bump when a generator changes what it writes.
GENERATOR_VERSION = 1

@dataclass(frozen=True)
class Table:
    """
    A table of the store: how to make it and what it is.

    Attributes
    ----------
    name : str
        Its file is ``name.npy``.
    generate : callable
        Returns the table (float64), deterministic: the same bits on every machine.
    spec : dict
        What the manifest records and checks (its ``shape`` among them); a change makes the table stale.
    source : callable
        A one-line description of its data's origin, for the manifest.
    """

    name: str
    generate: Callable[[], np.ndarray] = field(repr=False)
    spec: dict = field(repr=False)
    source: Callable[[], str] = field(repr=False, default=lambda: "computed by bragg-explorer")


#: The registered tables, by name (filled by the physics modules as they are imported).
TABLES: dict[str, Table] = {}


def register(name: str, generate: Callable[[], np.ndarray], spec: dict, source: Callable[[], str] | None = None) -> None:
    """Declare table ``name`` (see :class:`Table`); registering the same name again replaces it."""
    TABLES[name] = Table(name, generate, dict(spec), source or Table.__dataclass_fields__["source"].default)


def declared(name: str) -> Table:
    """The registered table ``name``, or a one-line error naming the registered ones."""
    try:
        return TABLES[name]
    except KeyError:
        known = ", ".join(sorted(TABLES)) or "none"
        raise KeyError(f"table {name!r} is not registered (registered: {known}); import the physics module "
                       "that declares it") from None


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
    if list(table.shape) != list(declared(name).spec["shape"]) or table.dtype != np.float64:
        return "not the recorded shape"
    return table


def _expected_spec(name: str) -> dict:
    return {**declared(name).spec, "generator_version": GENERATOR_VERSION, "dtype": "float64"}


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
    table = np.ascontiguousarray(declared(name).generate())
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
                "source": declared(name).source(),
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
        A registered table (:func:`register`).
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
            table = np.ascontiguousarray(declared(name).generate())
    table.setflags(write=False)
    _cache[key] = table
    return table
