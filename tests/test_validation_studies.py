"""
The measurements of docs/validation.md that no user command makes (``explorer.dev.validation_studies``),
each run on a tiny configuration: the tables' headers and shapes, and a few values that could be wrong.
The full sizes run in ``python -m explorer.dev.validation_doc`` only.
"""

from __future__ import annotations

import numpy as np
import pytest

from explorer.bench import markdown_tables as md
from explorer.dev import validation_doc
from explorer.dev import validation_studies as studies
from test_validation_doc import tables_in


def test_every_study_is_a_section_of_validation_md_with_its_command():
    sections = {s.name: s for s in validation_doc.SECTIONS}
    for name in studies.STUDIES:
        assert sections[name].command == f"python3 -m explorer.dev.validation_studies {name}"


def test_host_table():
    rows = studies.host_rows(lambdas=(500.0,), deltas=(0.25, 0.5), theta_degrees=np.linspace(0.0, 89.5, 7))
    header, *body = md.parse_markdown_table(studies.host_markdown(rows, angles=7))
    assert header == ["Λ (nm)", "δ", "basic", "paper s = 3", "improved s = 3", "1-nm sum"]
    assert [r[:2] for r in body] == [["500", "0.25"], ["500", "0.5"]]
    medians = {name: float(cell.split(" / ")[0]) for name, cell in zip(header[2:], body[1][2:])}
    # The 1-nm sum is close to the converged reference; the basic approximation is not, under a host.
    assert medians["1-nm sum"] < 0.5 < medians["basic"]


def test_exactness_tables():
    document = studies.exactness_rows(brute_force_n=(4,), growing_n=(4, 8), table_n=(4,), tmm_mirrors=3,
                                      grid=[(500.0, 0.5)], theta_degrees=np.linspace(0.0, 89.5, 5), step=0.05)
    tables = tables_in(studies.exactness_markdown(document))
    assert [t[0] for t in tables] == [["host", "max \\|R − R_tmm\\|"], ["N", "mirrors", "max relative error"],
                                      ["N", "max relative error", "ΔE2000 median / max", "converged reference"],
                                      ["N", "entries", "max relative error"]]
    assert [len(t) - 1 for t in tables] == [2, 1, 2, 1]
    assert max(document["tmm"]["no host"], document["tmm"]["host"]) < 1e-9  # Yeh equals the transfer matrices
    assert document["brute_force"][0]["mirrors"] == 1 + len(studies.HOST_MIRRORS)


@pytest.mark.gl
def test_lobes_table(gl_renderer):
    # The shared renderer: a second context made current in this process would leave the next module's shared
    # renderer drawing in it.
    document = studies.lobes_rows(tmm_stacks=3, fgd_samples=2, fgd_count=40, furnace_count=12, gl_size=(9, 7), lit_size=16,
                                  repeats=1, two_layer_samples=9, renderer=gl_renderer)
    header, *body = md.parse_markdown_table(studies.lobes_markdown(document))
    assert header == ["check", "result"] and len(body) == 9
    assert document["round_trip"]["cases"] == len(studies.INVERSE_CASES) and document["round_trip"]["energy"] < 1e-3
    assert document["highest"]["one_layer"] == pytest.approx(0.36)
    assert 0.0 < document["furnace"]["max_albedo"] <= 1.0 + 2e-3
    assert document["gl"]["max_relative"] <= 2e-3
    assert list(document["lit_ms"]) == ["GGX + Schlick", "1 interface", "2 interfaces", "3 interfaces", "4 interfaces"]
