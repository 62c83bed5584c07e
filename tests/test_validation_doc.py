"""
docs/validation.md written by commands (issue 21): the ``--markdown`` formatters of ``bench`` and
``accuracy`` on small synthetic documents, ``accuracy --markdown`` on a reduced Figure 4 grid, and
``explorer.dev.validation_doc`` with stubbed measurements (well-formed, atomic, ``--only``).
"""

from __future__ import annotations

import dataclasses
import functools
import re

import pytest

from conftest import run_cli
from explorer.bench import markdown_tables as md
from explorer.dev import validation_doc


def tables_in(text: str) -> list[list[list[str]]]:
    """Every Markdown table of ``text`` (an independent reader: header, separator, rows of equal width)."""
    tables, lines, i = [], text.splitlines(), 0
    while i < len(lines):
        if lines[i].startswith("|"):
            block = []
            while i < len(lines) and lines[i].startswith("|"):
                block.append(lines[i])
                i += 1
            rows = [[c.strip() for c in re.split(r"(?<!\\)\|", line.strip())[1:-1]] for line in block]
            assert len(rows) >= 2 and all(re.fullmatch(r":?-{3,}:?", c) for c in rows[1]), block[:2]
            assert {len(r) for r in rows} == {len(rows[0])}, block
            tables.append([rows[0], *rows[2:]])
        else:
            i += 1
    return tables


def test_markdown_table_and_its_parser_round_trip_and_escape_pipes():
    text = md.markdown_table(["a", "b|c"], [["1", "x|y"], [2.5, None]])
    assert md.parse_markdown_table("before\n\n" + text + "\nafter") == [["a", "b\0c"], ["1", "x\0y"], ["2.5", "None"]]
    assert tables_in(text)[0][0] == ["a", "b\\|c"]
    with pytest.raises(ValueError):
        md.markdown_table(["a", "b"], [["1"]])
    with pytest.raises(ValueError):
        md.parse_markdown_table("| a | b |\n| x | y |")


def _bench_document():
    rows = []
    for Lambda, reference_ms in ((244, 4000.0), (988, 3000.0)):
        for method, s, ms in (("reference", None, reference_ms), ("basic", None, 100.0), ("subdivided", 2, 200.0),
                              ("tabulated", None, 2.0), ("schlick", None, 1.5)):
            rows.append({"Lambda": Lambda, "method": method, "s": s, "ms": ms, "speedup": reference_ms / ms,
                         "dE_median": None if method == "schlick" else 0.5, "dE_max": None if method == "schlick" else 1.25})
    variants = [{"Lambda": L, "method": "improved", "s": 3, "ms": 250.0, "speedup": r / 250.0, "dE_median": 0.25, "dE_max": 2.0}
                for L, r in ((244, 4000.0), (988, 3000.0))]
    return {"device": "llvmpipe (test)", "size": 64, "repeats": 2, "rows": rows, "variants": variants,
            "table_rebuild_ms": {"244": 80.4, "988": 120.0}}


def test_bench_markdown_tables_hold_every_method_and_the_measured_speedups():
    text = md.bench_markdown(_bench_document())
    speed, accuracy = tables_in(text)
    assert speed[0] == ["Λ", "reference", "basic", "subdivided s = 2", "improved s = 3", "tabulated", "Schlick floor"]
    assert speed[1] == ["244 nm", "4.0 s", "×40.0", "×20.0", "×16.0", "×2000.0", "1.5 ms"]
    assert speed[2][1] == "3.0 s" and speed[2][2] == "×30.0"
    assert accuracy[0][1] == "reference (1-nm sum)" and accuracy[1][-2] == "0.25 / 2.0" and accuracy[1][1] == "0.50 / 1.2"
    assert "80 ms at Λ = 244 nm" in text and "64²" in text


def test_thin_film_and_app_markdown():
    document = {"device": "d", "size": 32, "repeats": 1, "view": "lit",
                "accuracy": [{"configuration": c, "method": m, "dE_median": 0.5 * i, "dE_max": 3.0}
                             for c in ("figure7", "soap") for i, m in enumerate(("rgb", "1-nm sum"), start=1)],
                "timing": [{"method": "spectral", "ms": 40.0, "relative": 20.0}, {"method": "ggx+schlick", "ms": 2.0, "relative": 1.0}]}
    accuracy, timing = tables_in(md.thin_film_markdown(document))
    assert accuracy == [["configuration", "rgb", "1-nm sum"], ["figure7", "0.5 / 3", "1 / 3"], ["soap", "0.5 / 3", "1 / 3"]]
    assert timing[1] == ["spectral", "40.00 ms", "×20.00"]
    rows = [{"mode": "lit", "method": 3, "name": "tabulated", "median_ms": 15.94, "fps": 62.7, "sphere_updates_per_s": 23.9,
             "while_dragging": "512x512 full"},
            {"mode": "env", "material": "bragg_stack.brd", "values": {"layers": 2}, "median_ms": 40.0, "fps": 25.0,
             "sphere_updates_per_s": 3.5, "first_pass_ms": 21.04, "drag_first_pass_median_ms": 30.0}]
    table = tables_in(md.app_markdown(rows))[0]
    assert table[1] == ["lit", "3 tabulated", "15.9 ms", "62.7", "23.9", "512x512 full"]
    assert table[2][0] == "env" and table[2][2:5] == ["40.0 ms", "25.0", "3.5"] and "first pass 21.0 ms" in table[2][5]


def test_layers_markdown_three_tables():
    slice_row = {"alpha": 0.1, "size": 16, "pixels": 100, "basic": {"dE_median": 4.05, "dE_max": 27.2},
                 "improved s=3": {"dE_median": 0.4, "dE_max": 4.4}, "tabulated": {"max_abs": 0.48, "max_relative": 8.2e-4}}
    document = {
        "timings": {"repeats": 3, "transmission_filter_ms": {"alpha=0.1": 26.6}, "layer_tables_ms": {"figure7_A": 172.0},
                    "goal_ms": {"transmission_filter_ms": 100.0, "layer_tables_ms": 10.0},
                    "paper_ms": {"transmission_filter_ms": 600.0, "layer_tables_ms": 40.0}},
        "slice": {"luminance_threshold": 0.01, "rows": [slice_row]},
        "stack": [{"preset": "figure7_A", "layers": 1, "tables_ms": 250.0, "frame_ms": 990.0, "size": 256, "pairs": 3000,
                   "lut_dE_median": 0.0, "lut_dE_max": 0.14}],
    }
    host, slices, stack = tables_in(md.layers_markdown(document))
    assert host[1:] == [["F_α, alpha=0.1", "26.6 ms", "100 ms", "600 ms"], ["layer tables, figure7_A", "172.0 ms", "10 ms", "40 ms"]]
    assert slices[0] == ["α", "pixels", "basic", "improved s=3", "tabulated"]
    assert slices[1] == ["0.1", "100", "4.05 / 27.2", "0.40 / 4.4", "0.48 / 8.2e-04"]
    assert stack[1] == ["figure7_A", "1", "250 ms", "0.99 s", "3000", "0.00 / 0.14"]


def test_accuracy_markdown_on_a_reduced_grid_parses(monkeypatch):
    """``accuracy --markdown``: the real measurement on one mirror and s = 2..3 (the grid reduced for speed)."""
    from explorer.bench import figure4 as bench  # the study's module, whose globals run_accuracy reads

    monkeypatch.setattr(bench, "FIGURE4_LAMBDAS", (500.0,))
    monkeypatch.setattr(bench, "FIGURE4_DELTAS", (0.5,))
    monkeypatch.setattr(bench, "figure4_accuracy", functools.partial(bench.figure4_accuracy, s_values=range(2, 4)))
    done = run_cli("accuracy", "--markdown")
    assert done.returncode == 0, done.stderr
    tables = tables_in(done.stdout)
    assert len(tables) == 3  # paper relative, paper absolute, improved
    for table in tables:
        assert table[0] == ["Λ (nm)", "δ", "basic", "s = 2", "s = 3", "1-nm sum"]
        assert table[1][:2] == ["500", "0.5"]
        for cell in table[1][2:]:
            median, maximum = (float(v) for v in cell.split(" / "))
            assert 0 <= median <= maximum
    assert run_cli("accuracy", "--markdown", "--json").returncode != 0


def _stub_sections(calls: list[str], fail: str | None = None):
    def measure(name):
        def table():
            calls.append(name)
            if name == fail:
                raise RuntimeError("no display here")
            return md.markdown_table(["quantity", "value"], [[name, "1.0 ms"]])
        return table
    return [dataclasses.replace(s, measure=measure(s.name)) for s in validation_doc.SECTIONS]


@pytest.fixture
def no_gl(monkeypatch):
    monkeypatch.setattr(validation_doc, "machine_description", lambda: "stub renderer, 2 CPUs")


def test_validation_doc_writes_a_well_formed_file(tmp_path, no_gl):
    calls: list[str] = []
    out = tmp_path / "validation.md"
    assert validation_doc.main(["--out", str(out)], sections=_stub_sections(calls)) == 0
    text = out.read_text(encoding="utf-8")
    measured = validation_doc.SECTIONS  # every table is written by a command
    assert calls == [s.name for s in measured]
    assert re.findall(r"(?m)^## (.+)$", text) == [s.title for s in validation_doc.SECTIONS]
    for section in measured:
        body = validation_doc.existing_sections(text)[section.name]
        assert f"Regenerate: `{section.command}`" in body and "stub renderer, 2 CPUs" in body
        assert tables_in(body)[0] == [["quantity", "value"], [section.name, "1.0 ms"]]
        if section.reduction:
            assert section.reduction in body
    for table in tables_in(text):
        assert table
    assert list(tmp_path.iterdir()) == [out]  # no temporary file left beside it


def test_validation_doc_only_keeps_the_other_sections_and_a_failure_keeps_its_text(tmp_path, no_gl):
    out = tmp_path / "validation.md"
    validation_doc.main(["--out", str(out)], sections=_stub_sections([]))
    before = validation_doc.existing_sections(out.read_text(encoding="utf-8"))
    calls: list[str] = []
    assert validation_doc.main(["--out", str(out), "--only", "bench"], sections=_stub_sections(calls)) == 0
    assert calls == ["bench"]
    after = validation_doc.existing_sections(out.read_text(encoding="utf-8"))
    assert {k: v for k, v in after.items() if k != "bench"} == {k: v for k, v in before.items() if k != "bench"}
    calls.clear()
    assert validation_doc.main(["--out", str(out), "--only", "app", "--only", "layers"],
                               sections=_stub_sections(calls, fail="app")) == 1
    assert calls == ["app", "layers"]
    assert validation_doc.existing_sections(out.read_text(encoding="utf-8"))["app"] == before["app"]


def test_validation_doc_is_atomic_when_interrupted(tmp_path, no_gl, monkeypatch):
    out = tmp_path / "validation.md"
    out.write_text("old\n", encoding="utf-8")

    def interrupted():
        raise KeyboardInterrupt

    sections = [dataclasses.replace(validation_doc.SECTIONS[0], measure=interrupted)]
    with pytest.raises(KeyboardInterrupt):
        validation_doc.main(["--out", str(out)], sections=sections)
    assert out.read_text(encoding="utf-8") == "old\n" and list(tmp_path.iterdir()) == [out]
    # The write itself fails at the rename (as a full disk would): the old file stays, no temporary is left.
    import os

    def failing_replace(*_):
        raise OSError(28, "No space left on device")

    replace = os.replace
    monkeypatch.setattr(os, "replace", failing_replace)
    assert validation_doc.main(["--out", str(out)], sections=_stub_sections([])) == 1
    monkeypatch.setattr(os, "replace", replace)
    assert out.read_text(encoding="utf-8") == "old\n" and list(tmp_path.iterdir()) == [out]
    bad = tmp_path / "validation.txt"
    assert validation_doc.main(["--out", str(bad)], sections=_stub_sections([])) == 1 and not bad.exists()


@pytest.mark.parametrize("args", [("bench", "--markdown", "--json"), ("bench", "--app", "--markdown"),
                                  ("bench", "--tables", "--markdown")])
def test_bench_markdown_rejects_what_it_cannot_format(args):
    done = run_cli(*args)
    assert done.returncode != 0 and len(done.stderr.strip().splitlines()) == 1 and "--markdown" in done.stderr


def test_the_committed_validation_md_has_every_section_and_well_formed_tables():
    from explorer.resources import SOURCE_ROOT

    text = (SOURCE_ROOT / validation_doc.DEFAULT_OUT).read_text(encoding="utf-8")
    assert list(validation_doc.existing_sections(text)) == list(validation_doc.NAMES)
    for section in validation_doc.SECTIONS:
        body = validation_doc.existing_sections(text)[section.name]
        tables = tables_in(body)  # every table well formed
        assert f"Regenerate: `{section.command}`" in body and tables
