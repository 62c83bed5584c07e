"""
``bragg-explorer accuracy --presets``: median and maximum ΔE2000 of every RGB method on every shipped
preset that holds a Bragg mirror, against the converged spectral reference, over the gradient view's angles.

Which mirrors (:func:`preset_mirrors`):

- ``bragg_mirror`` presets: the smooth mirror itself, host ``nh`` included (Appendix D);
- ``bragg_layer`` presets: the smooth mirror of the rough layer, whose ``method`` colours the microfacets;
- ``bragg_stack`` presets: each layer's mirror in the stack's host ``nh`` (Appendix D when ``n1_k != nh``),
  angles taken in the host. The stack itself is spectral (Eq. 34) and has no RGB method; its layers are
  listed because they are the paper's low-N and host mirrors (Figures 10-12, Table 3), which a user may
  load into ``bragg_mirror`` or ``bragg_layer``.

Identical mirrors are measured once and list every preset they come from. Methods: 1 basic, 2 subdivided
(s = 3), 4 improved (s = 3) and 3 tabulated as a check (its table is the converged spectra, interpolated).
The reference is :func:`explorer.physics.bragg.reference_rgb` (converged spectra, not the 1-nm sum).

References
----------
Fourneau, Pacanowski, Barla (2024). Interactive Exploration of Vivid Material Iridescence using Bragg
Mirrors. Computer Graphics Forum 43(2). Section 3.2, Appendix D, Table 3.
"""

from __future__ import annotations

import json
import sys
from dataclasses import dataclass, field

from explorer.materials.accuracy import ACCURACY_LIMIT, METHOD_NAMES, gradient_cos_theta, mirror_accuracy
from explorer.materials.methods import BraggMethod
from explorer.physics import bragg

#: The methods of the study, in table order (3 last: a check, exact by construction).
PRESET_METHODS = tuple(int(m) for m in (BraggMethod.BASIC, BraggMethod.SUBDIVIDED, BraggMethod.IMPROVED, BraggMethod.TABULATED))
#: The subdivided and improved methods' quality, the material's default.
PRESET_S = 3
#: Columns of the gradient view (its default width): θ = 90° (i + 0.5) / W.
PRESET_WIDTH = 256


@dataclass
class PresetMirror:
    """A Bragg mirror of the shipped presets, and where it comes from (``preset`` or ``preset/layer k``)."""

    mirror: bragg.BraggMirror
    sources: list[str] = field(default_factory=list)
    materials: set = field(default_factory=set)

    @property
    def name(self) -> str:
        more = len(self.sources) - 1
        return self.sources[0] + (f" (+{more})" if more else "")


def preset_mirrors(preset_files=None) -> list[PresetMirror]:
    """Every distinct Bragg mirror of the shipped presets (see the module docstring), in file order."""
    from explorer.materials.models import model_for
    from explorer.materials.twins import capabilities_of, twin_class
    from explorer.materials.presets import all_preset_files

    found: dict[bragg.BraggMirror, PresetMirror] = {}

    def add(mirror, source, material):
        entry = found.setdefault(mirror, PresetMirror(mirror))
        entry.sources.append(source)
        entry.materials.add(material)

    for preset_file in all_preset_files() if preset_files is None else preset_files:
        kind = preset_file.material.model
        capabilities = capabilities_of(preset_file.material)
        for name, preset in preset_file.presets.items():
            if capabilities.bragg_spectrum:  # one Bragg mirror
                model = model_for(preset_file.material, preset.resolve())
                if getattr(model, "natural", None) is not None:
                    continue  # absorbing, dispersive or disordered layers: every method shows the exact table
                add(model.mirror, name, kind)
            elif capabilities.supports("position-free"):  # a layered Bragg structure: each layer's mirror
                stack = twin_class(preset_file.material).stack_of(preset_file.material.typed_values(preset.resolve()))
                for k, layer in enumerate(stack.layers, start=1):
                    if layer.natural:
                        continue  # absorbing, dispersive or disordered: its exact tables, no approximation to rate
                    add(layer.mirror(stack.n1), f"{name}/layer {k}", kind)
    return list(found.values())


def preset_accuracy(mirrors: list[PresetMirror] | None = None, width: int = PRESET_WIDTH, progress=None) -> list[dict]:
    """One row per mirror: its parameters and, per method, median and max ΔE2000 over the gradient's angles."""
    mirrors = preset_mirrors() if mirrors is None else mirrors
    cos_theta = gradient_cos_theta(width)
    rows = []
    for index, entry in enumerate(mirrors):
        m = entry.mirror
        if progress is not None:
            progress(f"accuracy --presets: {index + 1}/{len(mirrors)} {entry.name}")
        reference = bragg.reference_rgb(cos_theta, m)
        accuracies = mirror_accuracy(m, PRESET_METHODS, s=PRESET_S, cos_theta=cos_theta, reference=reference)
        rows.append({
            "preset": entry.sources[0], "presets": entry.sources, "materials": sorted(entry.materials),
            "n1": m.n1, "n2": m.n2, "Lambda": m.Lambda, "delta": m.delta, "N": m.N, "nh": m.nh,
            "methods": {METHOD_NAMES[k]: {"method": k, "dE_median": a.dE_median, "dE_max": a.dE_max}
                        for k, a in accuracies.items()},
        })
    return rows


def exceptions(rows: list[dict]) -> dict[str, list[str]]:
    """Per method, the presets where its median ΔE2000 exceeds :data:`ACCURACY_LIMIT`."""
    result = {METHOD_NAMES[k]: [] for k in PRESET_METHODS}
    for row in rows:
        for name, value in row["methods"].items():
            if value["dE_median"] > ACCURACY_LIMIT:
                result[name].append(row["preset"])
    return result


def _host(row) -> str:
    return "n1" if row["nh"] is None else f"{row['nh']:g}"


def format_markdown(rows: list[dict], width: int = PRESET_WIDTH) -> str:
    """The per-preset table as Markdown, with the exceptions per method."""
    names = [METHOD_NAMES[k] for k in PRESET_METHODS]
    lines = [f"Median / max ΔE2000 over the gradient's {width} angles (θ = 90° (i + 0.5) / {width}) against the converged "
             f"spectral reference; s = {PRESET_S} for subdivided and improved; **bold**: median > {ACCURACY_LIMIT:g}.", ""]
    lines.append("| preset (+ identical mirrors) | n1 | n2 | Λ (nm) | δ | N | nh | " + " | ".join(
        f"{k} {n}" for k, n in zip(PRESET_METHODS, names)) + " |")
    lines.append("|---|---|---|---|---|---|---|" + "---|" * len(names))
    for row in rows:
        cells = []
        for n in names:
            v = row["methods"][n]
            median = f"{v['dE_median']:.2f}"
            cells.append((f"**{median}**" if v["dE_median"] > ACCURACY_LIMIT else median) + f" / {v['dE_max']:.1f}")
        more = len(row["presets"]) - 1
        label = row["preset"] + (f" (+{more})" if more else "")
        lines.append(f"| {label} | {row['n1']:g} | {row['n2']:g} | {row['Lambda']:g} | {row['delta']:g} | {row['N']} | "
                     f"{_host(row)} | " + " | ".join(cells) + " |")
    lines.append("")
    for name, presets in exceptions(rows).items():
        worst = max((r["methods"][name]["dE_median"] for r in rows), default=0.0)
        lines.append(f"- **{name}**: median > {ACCURACY_LIMIT:g} on {len(presets)} of {len(rows)} mirrors (worst median {worst:.2f})"
                     + (f": {', '.join(presets)}" if presets else ""))
    return "\n".join(lines)


def format_text(rows: list[dict], width: int = PRESET_WIDTH) -> str:
    """A plain table: median / max per method, ``!`` where the median exceeds the limit."""
    names = [METHOD_NAMES[k] for k in PRESET_METHODS]
    header = f"{'preset':<34} {'N':>4} {'nh':>5}  " + "  ".join(f"{n:>14}" for n in names)
    lines = [f"ΔE2000 median / max over the gradient's {width} angles vs the converged reference (! median > {ACCURACY_LIMIT:g})",
             header, "-" * len(header)]
    for row in rows:
        cells = []
        for n in names:
            v = row["methods"][n]
            flag = "!" if v["dE_median"] > ACCURACY_LIMIT else " "
            cells.append(f"{v['dE_median']:6.2f}{flag}/{v['dE_max']:5.1f}")
        more = len(row["presets"]) - 1
        label = (row["preset"] + (f" (+{more})" if more else ""))[:34]
        lines.append(f"{label:<34} {row['N']:>4} {_host(row):>5}  " + "  ".join(f"{c:>14}" for c in cells))
    lines.append("")
    for name, presets in exceptions(rows).items():
        lines.append(f"{name}: median > {ACCURACY_LIMIT:g} on {len(presets)} of {len(rows)} mirrors")
    return "\n".join(lines)


def run_preset_accuracy(as_json: bool = False, markdown: bool = False, width: int = PRESET_WIDTH) -> list[dict]:
    """Measure and print (text, ``--json`` or ``--markdown``)."""
    rows = preset_accuracy(width=width, progress=lambda m: print(m, file=sys.stderr, flush=True))
    if as_json:
        print(json.dumps({"width": width, "limit": ACCURACY_LIMIT, "s": PRESET_S, "rows": rows,
                          "exceptions": exceptions(rows)}, indent=2))
    elif markdown:
        print(format_markdown(rows, width))
    else:
        print(format_text(rows, width))
    return rows


def accuracy_note(material, values) -> str | None:
    """``render``'s one-line note when the chosen Bragg method is off here (None otherwise)."""
    from explorer.materials.accuracy import accuracy_badge

    badge = accuracy_badge(material, values)
    return None if badge is None else badge.note()
