"""
Which Mitsuba 3 variant to run, probed safely.

Mitsuba's LLVM variants JIT-compile through the system's libLLVM. With an LLVM older than 17 (Debian 12's
default 15) the first render aborts the whole process (SIGABRT, "Cannot select: fminimum"), which no
``try/except`` can catch. So the LLVM variants are first tried in a subprocess (:func:`llvm_works`): a
tiny render there either prints ``ok`` or dies alone, and this process falls back to the matching scalar
variant with a one-line note. ``python3 -m explorer`` installs Debian's ``libllvm19`` when the Mitsuba
extra is used (:mod:`explorer.dev.bootstrap`).
"""

from __future__ import annotations

import functools
import os
import subprocess
import sys
from typing import Callable

from explorer.errors import LocatedError

#: The variants the plugins support: RGB (the explorer's converged tables and colours) and spectral (the
#: physics at each path's wavelengths), JIT-compiled (LLVM) or scalar.
VARIANTS = ("llvm_ad_rgb", "llvm_ad_spectral", "scalar_rgb", "scalar_spectral")
#: The default: the explorer's own RGB colours, fast.
DEFAULT_VARIANT = "llvm_ad_rgb"
#: ``BRAGG_EXPLORER_MITSUBA_LLVM=0`` skips the probe and the LLVM variants (1 trusts them unprobed).
ENV_LLVM = "BRAGG_EXPLORER_MITSUBA_LLVM"
PROBE_TIMEOUT_S = 180

_PROBE = r"""
import mitsuba as mi
mi.set_variant("llvm_ad_rgb")
scene = mi.load_dict({"type": "scene", "integrator": {"type": "path"}, "s": {"type": "sphere"}, "e": {"type": "constant"},
    "sensor": {"type": "orthographic", "film": {"type": "hdrfilm", "width": 4, "height": 4},
               "sampler": {"type": "independent", "sample_count": 2}}})
image = mi.render(scene)
import drjit as dr
dr.eval(image)
print("ok", flush=True)
"""


class MitsubaError(LocatedError):
    """Mitsuba is missing, or a variant it cannot run (one line)."""


def is_spectral(variant: str) -> bool:
    return "spectral" in variant


def is_llvm(variant: str) -> bool:
    return variant.startswith("llvm")


def scalar_counterpart(variant: str) -> str:
    return "scalar_spectral" if is_spectral(variant) else "scalar_rgb"


@functools.lru_cache(maxsize=1)
def llvm_works() -> bool:
    """Whether Mitsuba's LLVM variants render here, tried in a subprocess (an old libLLVM aborts it, not us)."""
    forced = os.environ.get(ENV_LLVM, "")
    if forced in ("0", "1"):
        return forced == "1"
    try:
        result = subprocess.run([sys.executable, "-c", _PROBE], capture_output=True, text=True,
                                timeout=PROBE_TIMEOUT_S, stdin=subprocess.DEVNULL)
    except (OSError, subprocess.SubprocessError):
        return False
    return result.returncode == 0 and "ok" in result.stdout


def mitsuba_available() -> bool:
    try:
        import mitsuba  # noqa: F401
    except ImportError:
        return False
    return True


def choose_variant(requested: str | None = None, note: Callable[[str], None] | None = None) -> str:
    """
    The variant to run: ``requested`` (default :data:`DEFAULT_VARIANT`), or its scalar counterpart with a
    one-line ``note`` when it is an LLVM variant that :func:`llvm_works` finds unusable.
    """
    variant = requested or DEFAULT_VARIANT
    if variant not in VARIANTS:
        raise MitsubaError("--variant", None, f"unknown Mitsuba variant {variant!r} (one of {', '.join(VARIANTS)})")
    if not mitsuba_available():
        raise MitsubaError("mitsuba", None, "Mitsuba 3 is not installed: pip install '.[mitsuba]' (or run through python3 -m explorer)")
    if is_llvm(variant) and not llvm_works():
        fallback = scalar_counterpart(variant)
        if note is not None:
            note(f"Mitsuba's LLVM variants cannot run here (libLLVM >= 17 missing): {fallback} instead of {variant}, slower")
        return fallback
    return variant
