"""``bragg-explorer bench --tables`` and ``--scaling`` (issue 22): their documents, on a small scale."""

from __future__ import annotations

import json

import pytest

from conftest import run_cli_process as cli


@pytest.mark.gl
def test_bench_tables_json(gl_renderer):
    run = cli("bench", "--tables", "--json", "--repeats", "1", "--size", "32")
    assert run.returncode == 0, run.stderr
    document = json.loads(run.stdout)
    assert set(document["table_ms"]) == set(document["table_cpu_ms"]) == {"20", "100", "1000"}
    assert set(document["tabulated_over_schlick"]) == set(document["tabulated_over_schlick_cpu"]) == {"244", "500", "988"}
    # The same run times the table in a 2D texture (the path before buffer tables): before/after in one document.
    assert set(document["tabulated_2d_over_schlick"]) == set(document["tabulated_2d_over_schlick_cpu"]) == {"244", "500", "988"}
    values = [*document["table_ms"].values(), *document["table_cpu_ms"].values(), document["layer_tables_ms"],
              document["layer_tables_cpu_ms"], *document["tabulated_over_schlick"].values(),
              *document["tabulated_2d_over_schlick"].values()]
    assert all(v > 0.0 for v in values)


@pytest.mark.gl
def test_bench_scaling_document_and_plot(gl_renderer, monkeypatch, tmp_path, capsys):
    from explorer.bench import scaling as bench  # the study's module, whose globals scaling_study reads

    monkeypatch.setattr(bench, "SCALING_N", (1, 20))
    monkeypatch.setattr(bench, "SCALING_ANGLES", (17, 33))
    monkeypatch.setattr(bench, "SCALING_SPHERES", (16, 32))
    plot = tmp_path / "scaling.png"
    # The session's renderer: a second GL context made current here would leave the other tests' one stale.
    document = bench.run_scaling_bench(as_json=True, repeats=1, plot=plot, renderer=gl_renderer)
    assert json.loads(capsys.readouterr().out) == document
    assert [r["N"] for r in document["N"]] == [1, 20] and [r["size"] for r in document["spheres"]] == [16, 32]
    assert {(r["N"], r["angles"]) for r in document["angles"]} == {(20, 17), (20, 33), (1000, 17), (1000, 33)}
    assert all(r["table_ms"] > 0.0 and r["reference_rule_65_cpu_ms"] > 0.0 for r in document["N"])
    assert plot.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and not list(tmp_path.glob(".scaling.png.*"))


def test_bench_scaling_bad_plot_path_is_one_line():
    run = cli("bench", "--scaling", "--plot", "/nonexistent-directory/scaling.png")
    assert run.returncode != 0 and "Traceback" not in run.stderr
    assert "does not exist" in run.stderr.strip().splitlines()[-1]
