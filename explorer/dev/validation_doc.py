"""
``python -m explorer.dev.validation_doc [--only NAME ...] [--out docs/validation.md]``: run every measurement
of ``docs/validation.md`` in-process and write the file atomically, so that its tables cannot go stale.

Each table is a :class:`Section` of :data:`SECTIONS` (one registry; ``--only`` and the file's order derive
from it): a heading, the command that regenerates the table, the date and machine (GL renderer, CPU count),
the short fixed prose that explains it, and the Markdown the command prints (``bench``/``accuracy
--markdown`` through :mod:`explorer.bench.markdown_tables`, or :mod:`explorer.dev.validation_studies` for the
measurements no user command makes: under a host, exactness, the layered lobes). Slow measurements run reduced (a smaller sphere, fewer repeats), and
the reduction is written beside the table. With ``--only``, the other sections keep their text from the
existing file.

References
----------
Fourneau, Pacanowski, Barla (2024). Interactive Exploration of Vivid Material Iridescence using Bragg
Mirrors. Computer Graphics Forum 43(2). Table 1, Figure 4, Section 5 (rough layers), Table 2.
"""

from __future__ import annotations

import argparse
import contextlib
import datetime
import io
import os
import re
import sys
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

from explorer import resources
from explorer.errors import OutputError
from explorer.files import write_text_atomic
from explorer.materials.models import BraggStackModel
from explorer.materials.thinfilm_model import ThinFilmModel

DEFAULT_OUT = Path("docs/validation.md")

INTRO = """# Validation

Every measured table of the project, written by `python -m explorer.dev.validation_doc` (do not edit by
hand: rerun it, or `--only NAME` for one table). Each section names the command that regenerates its
table, when and on which machine it ran. Times depend on the machine and its load: compare ratios within
one table, not milliseconds across tables."""


@dataclass(frozen=True)
class Section:
    """One table of ``docs/validation.md``: how to measure it and the fixed text around it."""

    name: str
    title: str
    command: str
    #: Measures and returns the table(s) as Markdown (no printing to stdout).
    measure: Callable[[], str]
    prose: str = ""
    after: str = ""
    #: How this run differs from ``command``'s defaults (a smaller sphere, fewer repeats), or "".
    reduction: str = ""


def _quiet(function, *args, **kwargs):
    """``function``'s result with its stdout discarded (the commands print; the document is what we format)."""
    with contextlib.redirect_stdout(io.StringIO()):
        return function(*args, **kwargs)


def _app() -> str:
    import json
    import subprocess

    from explorer.bench.markdown_tables import app_markdown
    from explorer.resources import SOURCE_ROOT

    # In a child process: the app's window context (GLX) cannot be made current in a process that
    # already made an EGL context current (Xlib then exits the whole process on BadAccess).
    done = subprocess.run([sys.executable, "-c", APP_CHILD.format(frames=APP_FRAMES)], cwd=SOURCE_ROOT,
                          capture_output=True, text=True, timeout=1200)
    if done.returncode != 0:
        raise RuntimeError((done.stderr.strip().splitlines() or ["no output"])[-1])
    return app_markdown(json.loads(done.stdout)["rows"])


APP_CHILD = ("import json, contextlib, io, sys\n"
             "from explorer.bench import run_app_bench\n"
             "with contextlib.redirect_stdout(io.StringIO()):\n"
             "    rows = run_app_bench(as_json=True, size=512, frames={frames})\n"
             "print(json.dumps({{'rows': rows}}))\n")


def _accuracy() -> str:
    from explorer.bench import FIGURE4_DELTAS, FIGURE4_LAMBDAS, figure4_accuracy
    from explorer.bench.markdown_tables import accuracy_markdown

    return accuracy_markdown(figure4_accuracy(), FIGURE4_LAMBDAS, FIGURE4_DELTAS)


def _bench() -> str:
    from explorer.bench import run_bench
    from explorer.bench.markdown_tables import bench_markdown

    return bench_markdown(_quiet(run_bench, as_json=True, size=BENCH_SIZE, repeats=BENCH_REPEATS))


def _thin_film() -> str:
    from explorer.bench import run_thin_film_bench
    from explorer.bench.markdown_tables import thin_film_markdown

    return thin_film_markdown(_quiet(run_thin_film_bench, as_json=True, size=BENCH_SIZE, repeats=BENCH_REPEATS))


def _layers() -> str:
    from explorer.bench import run_layers_bench
    from explorer.bench.markdown_tables import layers_markdown

    return layers_markdown(_quiet(run_layers_bench, as_json=True, repeats=LAYERS_REPEATS))


def _study(name: str) -> Callable[[], str]:
    """A table of :mod:`explorer.dev.validation_studies` (the measurements no user command makes)."""
    def measure() -> str:
        from explorer.dev.validation_studies import STUDIES

        return STUDIES[name](lambda message: print(message, file=sys.stderr, flush=True))
    return measure


#: Reductions of the slow measurements (the commands' defaults: 60 frames, a 512² sphere, 5 layer repeats).
APP_FRAMES = 60
BENCH_SIZE = 256
BENCH_REPEATS = 3
LAYERS_REPEATS = 3

SECTIONS: tuple[Section, ...] = (
    Section(
        "app", "The app's frame times", "python3 -m explorer bench --app", _app,
        prose="Frame times while dragging Λ (only frames where Λ changed), a scripted session (Xvfb when there is "
              "no display), 512² sphere in a 1280×800 window. Views that cost more than a frame are drawn at reduced "
              "resolution while a slider moves and refined in bands afterwards; the host's tables are built on a "
              "worker thread, so the sphere shows the newest values whose tables are ready (at most a frame behind).",
        after="While a slider moves, the tabulated method shows a draft table from the paper's 1-nm sum (~10 ms), "
              "replaced by the converged table on release. On llvmpipe the window's own drawing (ImGui, the sphere "
              "drawn three times) costs most of the tabulated row.",
        reduction="" if APP_FRAMES == 60 else f"{APP_FRAMES} drag frames per method (the command's default: 60)"),
    Section(
        "accuracy", "Accuracy of the Bragg mirror's approximations (Figure 4)", "python3 -m explorer accuracy --markdown",
        _accuracy,
        prose="The approximations against the converged spectral reference (`bragg.reference_rgb`) on the grid of "
              "Figure 4 (n1 = 1, n2 = 1.5, N = 20; 180 angles θ ∈ [0°, 89.5°]). The last column is the paper's 1-nm "
              "sum's own error against the same reference, for scale. The subdivision rule `max(1, s − m)` leaves open "
              "how the mode index m is counted: **relative** numbers from the first band overlapping the visible range "
              "(the reading consistent with the paper's Table 1), **absolute** from mode 0.",
        after="The goal is a median ΔE2000 ≤ 2 at s = 3: compare the paper's variant with the improved one (method 4, "
              "same box budget, sub-boxes by share of CMF mass)."),
    Section(
        "host", "Accuracy under a host medium (Appendix D)", "python3 -m explorer.dev.validation_studies host", _study("host"),
        prose="Under a host nh ≠ n1 (Appendix D) the host interface reflects coherently with the mirror. The improved "
              "method weights each box with the fringes' average of Appendix D's |r_hN|² itself: with x = cot(N K Λ), "
              "r_hN = (P + Q x) / (S + T x) is a Möbius map of x, and x sweeps the real line with a Cauchy density over "
              "a fringe, so the average is a closed form by residues (`bragg.fringe_average_under_host`). Applying the "
              "host interface incoherently to the no-host average instead misses a slow modulation of R of up to ~0.07 "
              "(water-like layers in air). Columns: the basic method, the subdivided method in the paper's variant and in "
              "ours (improved, method 4), and the paper's 1-nm sum."),
    Section(
        "bench", "Speed of the Bragg mirror's methods (Table 1)", "python3 -m explorer bench --markdown", _bench,
        prose="Time per frame of a sphere (bounded by `glFinish`), Λ ∈ {244, 500, 988} nm (n1 = 1, n2 = 1.5, δ = 0.5, "
              "N = 20), interleaved repeats, medians. The paper's speed-ups (GPU, 244 / 500 / 988 nm): basic ×10.6 / 6.8 / "
              "4.2, s = 2 ×8.8 / 5.0 / 3.8, s = 3 ×5.5 / 3.5 / 3.1, s = 4 ×4.5 / 2.6 / 2.4, s = 5 ×3.8 / 2.1 / 1.7.",
        after="Each method is compiled as its own program (`# specialise: method`), so the tabulated sphere costs one "
              "texture fetch per pixel, close to a plain Schlick-Fresnel shader. Without a GPU (llvmpipe) the "
              "reference's loop dominates, so the speed-ups exceed the paper's.",
        reduction=f"a {BENCH_SIZE}² sphere (the command's default: 512²)"),
    Section(
        "exactness", "Exactness of the Bragg mirror and its converged reference",
        "python3 -m explorer.dev.validation_studies exactness", _study("exactness"),
        prose="*The converged reference.* Beside band edges, Yeh's reflectance has transmission resonances narrower "
              "than a nanometre (narrower as N grows, ∝ 1/N³ for the first ones), which the paper's 1-nm samples hit or "
              "miss. `bragg.reference_rgb` (numpy, no step) integrates R_λ against the CMFs interpolated linearly between "
              "their 1-nm nodes: that equals the 1-nm sum with each sample R(λ_i) replaced by R's average over the hat "
              "function of node i, so white and the XYZ → RGB matrix stay those of the 1-nm sum. The averages are refined "
              "per 1-nm cell (`colorimetry.converged_spectra`): trapezoid sums every 1/K nm, Richardson-extrapolated "
              "between successive K (Simpson's rule), K doubling until one comparison changes the cell's share of the "
              "colour by less than 2e-4 of the row's brightest channel divided among the 472 cells; only the cells beside "
              "band edges and under narrow resonances refine further (to 1/1024 nm). Thin films "
              f"(`thinfilm.reference_rgb`) and the layer tables of `{BraggStackModel.name}.brd` (Eq. 28) use the same hat averages.",
        after="*The table* (method 3) refines where the second differences of its 256 entries say that linear "
              "interpolation may miss by more than 5e-4, up to 4081 entries (the colour turns fastest near Brewster's "
              "angle, where the p band gap closes). *GL, method 0*: `wavelength_step = 1` is the paper's sum; at 1/32 nm "
              "the shader equals the converged numpy reference to 2e-3 of the brightest channel, and every GL image equals "
              "its numpy twin to 2e-3 per linear channel (tests/test_converged.py, the twins' tests). In float32, a mirror "
              "with N = 1000 and total internal reflection in layer 2 differs from float64 by up to ~3.5e-3 in isolated "
              "columns, and so does θ = 89.75°, beyond the 89.5° in scope."),
    Section(
        "thin-film", "Thin films (Belcour & Barla 2017)", "python3 -m explorer bench --thin-film --markdown", _thin_film,
        prose=f"ΔE2000 of the thin-film methods of `{ThinFilmModel.name}.brd` on Figure 7's film and every thin-film preset, and "
              "their frame time on a lit sphere relative to plain GGX with Schlick's Fresnel.",
        reduction=f"a {BENCH_SIZE}² sphere (the command's default: 512²)"),
    Section(
        "layers", "Rough layers and stacks", "python3 -m explorer bench --layers --markdown", _layers,
        prose="Host tables: every F_α built from scratch (a new α), a layer's tables (Yeh's R_λ over θ and the "
              "integrated transmissivity of Eq. 28, hat averages converged per nm cell) timed without their F_α. "
              "Slice view (θh across, θd down, φd = 90°) of the Figure 8 layer (Λ = 500 nm, δ = 0.5, N = 20) with "
              "ρd = 0: each approximation against the converged reference per pixel, over pixels with Y > 0.01; where "
              "the lobe is brighter than white (grazing rows) L* exceeds 100 and the maxima come from there. Stacks "
              f"(`{BraggStackModel.name}.brd`): the tables' rebuild after a parameter change, the GL time of a `lit` frame, and "
              "how far the tabulated R_λ (Table 2's Model-LUT) moves Eq. 34 from Yeh's R_λ at the exact angle (Model).",
        after="With ρd = 0 every method shares the lobe D G1 G1 / (4 cos θi cos θo) and differs only in R_rgb(θd). "
              "Tables under Appendix D's host take the complex float64 path of Yeh's reflectance, hence their cost.",
        reduction=f"{LAYERS_REPEATS} repeats (the command's default: 5)"),
    Section(
        "lobes", "Layered lobes (Bati et al. 2021)", "python3 -m explorer.dev.validation_studies lobes", _study("lobes"),
        prose="The checks of `tests/test_lobes.py` and `tests/test_inverse.py`, measured on more cases than the tests "
              "hold (a result's \"bound\" is its test's tolerance).",
        after="Known limits: Eq. 3 takes R_k and σ_k at the light's angle, so the BRDF is reciprocal only for pairs of "
              "equal polar angle (tested there). Near the critical angle of an interface seen from its denser side "
              "(η < 1) with α < 0.1, the 33-node FGD table misses TIR's sharp rise (hence η > 1 above). Rough conductors "
              "use E(θ, α) F(c̄_d) instead of Belcour's 4D table; Belcour's TIR term is not used (Bati et al. find it "
              "negligible at normal incidence); instead `tir` (off by default, `inverse --tir`) lets light going up a "
              "rough interface see the FGD of its own side. Coloured 2-layer lobes reach the requested variance on one "
              "channel only (Sec. 5.2.3). The white furnace stays below 1 because Eq. 3's GGX lobes lose their "
              "shadowing once more after FGD."),
)

NAMES = tuple(section.name for section in SECTIONS)


def machine_description() -> str:
    """The GL renderer string (an EGL standalone context) and the CPU count, for the section headers."""
    try:
        import moderngl

        context = moderngl.create_standalone_context(backend="egl")
        try:
            renderer = context.info.get("GL_RENDERER", "unknown renderer")
        finally:
            context.release()
    except Exception as error:  # no GL here: say so rather than fail the whole document
        renderer = f"no GL context ({type(error).__name__})"
    return f"{renderer}, {os.cpu_count()} CPUs"


def _marker(name: str) -> str:
    # An HTML comment GitHub does not show: it delimits a section so --only can keep the others.
    return f"<!-- validation_doc: {name} -->"


def render_section(section: Section, table: str, when: str, machine: str) -> str:
    """One section's Markdown: heading, command, date and machine, reduction, prose, table, closing prose."""
    lines = [_marker(section.name), f"## {section.title}", "", f"Regenerate: `{section.command}`  ",
             f"Measured {when} on {machine}" + (f"; reduced: {section.reduction}." if section.reduction else "."), ""]
    if section.prose:
        lines += [section.prose, ""]
    lines += [table.rstrip(), ""]
    if section.after:
        lines += [section.after, ""]
    return "\n".join(lines)


def existing_sections(text: str) -> dict[str, str]:
    """The sections of a file this script wrote, by name (for ``--only``)."""
    parts = re.split(r"(?m)^(<!-- validation_doc: ([\w-]+) -->)$", text)
    return {parts[i + 1]: (parts[i] + parts[i + 2]).rstrip() + "\n" for i in range(1, len(parts) - 2, 3)}


def build_document(sections: Sequence[Section], only: Sequence[str] | None = None, previous: str = "",
                   machine: str | None = None, now: datetime.datetime | None = None, progress=None,
                   failures: list[str] | None = None) -> str:
    """
    The whole file: :data:`INTRO` and every section, measuring those named in ``only`` (all when None)
    and keeping the others' text from ``previous`` (a placeholder when it has none). A measurement that
    fails keeps its previous text too, and its one-line reason is appended to ``failures``.
    """
    machine = machine_description() if machine is None else machine
    when = (now or datetime.datetime.now(datetime.timezone.utc)).strftime("%Y-%m-%d %H:%M UTC")
    kept = existing_sections(previous)
    parts = [INTRO, ""]
    for section in sections:
        if only is None or section.name in only:
            if progress is not None:
                progress(f"validation_doc: measuring {section.name} ({section.command})")
            try:
                parts.append(render_section(section, section.measure(), when, machine))
                continue
            except Exception as error:  # one failed table (no Xvfb, no GL) must not lose the others
                reason = f"{section.name}: {type(error).__name__}: {str(error).splitlines()[0] if str(error) else ''}"
                if failures is not None:
                    failures.append(reason)
                if progress is not None:
                    progress(f"validation_doc: {reason} (its previous text is kept)")
        parts.append(kept.get(section.name) or
                         f"{_marker(section.name)}\n## {section.title}\n\nNot measured yet: `{section.command}`.\n")
    return "\n".join(parts).rstrip() + "\n"


def main(argv: Sequence[str] | None = None, sections: Sequence[Section] = SECTIONS) -> int:
    parser = argparse.ArgumentParser(prog="python -m explorer.dev.validation_doc", description=__doc__.split("\n\n")[0])
    parser.add_argument("--only", action="append", choices=[s.name for s in sections], metavar="NAME",
                        help="measure only this table (repeatable): " + ", ".join(s.name for s in sections))
    parser.add_argument("--out", type=Path, help=f"the file to write (default: the checkout's {DEFAULT_OUT})")
    arguments = parser.parse_args(argv)
    resources.require_checkout("python -m explorer.dev.validation_doc")
    out: Path = arguments.out or resources.CHECKOUT_ROOT / DEFAULT_OUT
    try:
        previous = out.read_text(encoding="utf-8") if out.is_file() else ""
        failures: list[str] = []
        text = build_document(sections, arguments.only, previous,
                              progress=lambda m: print(m, file=sys.stderr, flush=True), failures=failures)
        write_text_atomic(out, text, (".md",))
    except OutputError as error:
        print(f"error: {error}", file=sys.stderr)
        return 1
    print(f"wrote {out}" + (f"; {len(failures)} table(s) not measured: " + "; ".join(failures) if failures else ""),
          file=sys.stderr)
    return 1 if failures else 0


if __name__ == "__main__":
    raise SystemExit(main())
