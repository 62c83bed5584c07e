"""
The constants the GLSL library shares with the physics, generated from the Python ones at shader assembly.

A library file includes its module's block, ``#include "generated/thinfilm.glsl"``; the preprocessor
(:class:`explorer.materials.glsl.ShaderBuilder`) writes it from :data:`GENERATED` instead of reading a
file, so every number below has one source, the physics module named beside it, and no hand copy.
Floats are written with ``repr`` (shortest round trip: the float32 the driver parses is the float32 of
the Python value).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping

import numpy as np

from explorer.physics import bragg, colorimetry, compensation, layered, lobes, lobes_fgd, microfacet, multiscatter_stack, structure_maps, thinfilm


def declaration(name: str, value) -> str:
    """``const int|float|vec3 NAME = value;`` for an int, a float or three floats."""
    if isinstance(value, (bool, np.bool_)):
        raise TypeError(f"{name}: booleans are not shared constants")
    if isinstance(value, (int, np.integer)):
        return f"const int {name} = {int(value)};"
    if isinstance(value, (float, np.floating)):
        return f"const float {name} = {_float(value)};"
    values = tuple(float(v) for v in value)
    if len(values) != 3:
        raise ValueError(f"{name}: a vector constant has 3 components, got {len(values)}")
    return f"const vec3 {name} = vec3({', '.join(_float(v) for v in values)});"


def _float(value) -> str:
    text = repr(float(value))
    if not np.isfinite(float(value)):
        raise ValueError(f"not a finite constant: {text}")
    return text if any(c in text for c in ".eE") else text + ".0"


def _block(constants: Mapping[str, object], source: str) -> str:
    lines = [f"// Generated at assembly from {source} (explorer/materials/shader_constants.py)."]
    return "\n".join(lines + [declaration(name, value) for name, value in constants.items()]) + "\n"


#: ``{include name: the block's text}``, each from the physics module the library file twins.
GENERATED: dict[str, Callable[[], str]] = {
    "generated/bragg.glsl": lambda: _block({
        "BISECTION_STEPS": bragg.BISECTION_STEPS,
        "WAVELENGTH_LOW": bragg.WAVELENGTH_LOW,
        "WAVELENGTH_HIGH": bragg.WAVELENGTH_HIGH,
        "OMEGA_LOW": bragg.OMEGA_LOW,
        "OMEGA_HIGH": bragg.OMEGA_HIGH,
        "COS_THETA_MIN": bragg.COS_THETA_MIN,
        "MAX_DECAY": bragg.MAX_DECAY,
        "FRINGE_B_MIN": bragg.FRINGE_B_MIN,
        "FRINGE_Q_MIN": bragg.FRINGE_Q_MIN,
        "FRINGE_RESOLVE_NM": bragg.FRINGE_RESOLVE_NM,
        "SAMPLES_PER_FRINGE": bragg.SAMPLES_PER_FRINGE,
        "RESOLVE_BUDGET": bragg.RESOLVE_BUDGET,
        "N_RESOLVE": bragg.N_RESOLVE,
        "GROW_EXPONENT": bragg.GROW_EXPONENT,
        "MAX_RESOLVED_PIECES": bragg.MAX_RESOLVED_PIECES,
    }, "explorer/physics/bragg/"),
    "generated/structure_maps.glsl": lambda: _block({
        "TEXTURE_MAPS": structure_maps.MAPS_MAPPING,
        "STRUCTURE_TEXELS": structure_maps.STRUCTURE_TEXELS,
    }, "explorer/physics/structure_maps.py"),
    "generated/colorimetry.glsl": lambda: _block({
        "CMF_COUNT": colorimetry.WAVELENGTHS.size,
        "CMF_FIRST_WAVELENGTH": float(colorimetry.WAVELENGTH_MIN),
        "CUMULATIVE_START": colorimetry.CUMULATIVE_START,
        "CUMULATIVE_SIZE": float(colorimetry.WAVELENGTHS.size + 1),
    }, "explorer/physics/colorimetry.py"),
    "generated/microfacet.glsl": lambda: _block({
        "ALPHA_MIN": microfacet.ALPHA_MIN,
    }, "explorer/physics/microfacet.py"),
    "generated/layered.glsl": lambda: _block({
        "MAX_LAYERS": layered.MAX_LAYERS,
        "THETA_ROWS": microfacet.THETA_COUNT,
        "THETA_STEP": float(microfacet.THETA_STEP),
        "LAYER_COS_THETA_MIN": microfacet.COS_THETA_MIN,
    }, "explorer/physics/layered.py and microfacet.py"),
    "generated/multiscatter.glsl": lambda: _block({
        "COMPENSATION_ROWS": multiscatter_stack.TABLE_ROWS,
        "COMPENSATION_STEP_DEG": float(multiscatter_stack.TABLE_STEP_DEG),
        "COMPENSATION_FADE_START": compensation.FADE_START,
        "COMPENSATION_FADE_END": compensation.FADE_END,
    }, "explorer/physics/multiscatter_stack.py and compensation.py"),
    "generated/lobes.glsl": lambda: _block({
        "LOBES_MAX": lobes.MAX_INTERFACES,
        "FGD_COS_COUNT": lobes_fgd.FGD_COS_COUNT,
        "FGD_ALPHA_COUNT": lobes_fgd.FGD_ALPHA_COUNT,
        "FGD_ETA_COUNT": lobes_fgd.FGD_ETA_COUNT,
        "ETA_TABLE_MAX": lobes_fgd.ETA_TABLE_MAX,
        "LOBES_COS_MIN": lobes.COS_MIN,
        "VARIANCE_MAX": lobes.VARIANCE_MAX,
    }, "explorer/physics/lobes.py and lobes_fgd.py"),
    "generated/thinfilm.glsl": lambda: _block({
        "FILM_COS_THETA_MIN": thinfilm.COS_THETA_MIN,
        "NAIVE_WAVELENGTHS": thinfilm.NAIVE_WAVELENGTHS,
        "SENSITIVITY_FOURIER_STEP": thinfilm.SENSITIVITY_FOURIER_STEP,
        "SENSITIVITY_FOURIER_CARRIER_NM": thinfilm.SENSITIVITY_FOURIER_CARRIER_NM,
        "GAUSSIAN_FIT_VAL": thinfilm.GAUSSIAN_FIT_VAL,
        "GAUSSIAN_FIT_POS": thinfilm.GAUSSIAN_FIT_POS,
        "GAUSSIAN_FIT_VAR": thinfilm.GAUSSIAN_FIT_VAR,
        "GAUSSIAN_FIT_X2": thinfilm.GAUSSIAN_FIT_X2,
        "GAUSSIAN_FIT_NORM": thinfilm.GAUSSIAN_FIT_NORM,
        "REMAINDER_MIN": thinfilm.REMAINDER_MIN,
        "PREFILTER_SIGMA_STEP": thinfilm.PREFILTER_SIGMA_STEP,
        "PREFILTER_LEVELS": thinfilm.PREFILTER_LEVELS,
        "D_INC_BLEND": thinfilm.D_INC_BLEND,
    }, "explorer/physics/thinfilm/"),
}
