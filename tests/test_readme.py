"""The README is a user's document that works: short, and every command in it runs.

Every ``python3 -m explorer …`` line of its ``sh`` blocks is run (in a subprocess from a scratch folder,
outputs redirected there), except the two commands' own lines (the app, the test suite) and the ones
:data:`EXPENSIVE` names; each must exit 0 and write the file its ``--out`` names.
"""

from __future__ import annotations

import re
import shlex
from pathlib import Path

import pytest

from conftest import REPO_ROOT, run_cli_process

README = REPO_ROOT / "README.md"
#: The README's length limit (a user's document: details live in docs/).
MAX_LINES = 220
#: Commands not run here, and why: the two commands themselves (the app; the suite that runs this test).
NOT_RUN = ("python3 -m explorer test", "python3 -m explorer open")
#: Sub-commands that take minutes on this machine; the benchmarks have their own tests.
EXPENSIVE = ("bench",)


def readme_commands() -> list[str]:
    blocks = re.findall(r"```sh\n(.*?)```", README.read_text(encoding="utf-8"), flags=re.S)
    commands = []
    for block in blocks:
        for line in block.splitlines():
            line = line.split("  #")[0].strip()
            if line.startswith("python3 -m explorer") and line != "python3 -m explorer":
                commands.append(line)
    return commands


def test_readme_is_short():
    lines = README.read_text(encoding="utf-8").count("\n")
    assert lines <= MAX_LINES, f"README.md has {lines} lines (at most {MAX_LINES}: move details to docs/)"


def test_readme_has_commands_to_run():
    commands = readme_commands()
    assert len([c for c in commands if c.split()[3] == "render"]) >= 3, commands


CHEAP = [c for c in readme_commands() if not c.startswith(NOT_RUN) and c.split()[3] not in EXPENSIVE]


@pytest.mark.gl
@pytest.mark.parametrize("command", CHEAP, ids=[c.split()[3] + "-" + str(i) for i, c in enumerate(CHEAP)])
@pytest.mark.slow
def test_readme_command_runs(command, tmp_path, gl_renderer):
    argv = shlex.split(command)[3:]
    if "--out" in argv:  # write into the scratch folder, under the README's file name
        index = argv.index("--out") + 1
        argv[index] = str(tmp_path / Path(argv[index]).name)
    run = run_cli_process(*argv, cwd=REPO_ROOT)
    assert run.returncode == 0, f"{command}\n{run.stderr}"
    if "--out" in argv:
        out = Path(argv[argv.index("--out") + 1])
        assert out.is_file() and out.stat().st_size > 0, f"{command}: no {out.name}"
