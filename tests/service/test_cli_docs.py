"""The documentation is true to the command line: every documented example runs and answers as shown.

An example is a ``$ command`` line in a fenced block of README.md or docs/*.md (a trailing ``\\`` continues
it); the lines after it, up to the next ``$`` or the end of the block, are its documented output. The README's
indented set-up commands count from their ``.venv/bin/sphereplan`` part. Examples of one file run in order in
one scratch folder (``maps/`` is the repository's), so a file written by one example feeds the next, as it
would for a reader typing them. Each must exit 0; an output documented as JSON must be JSON on stdout and
carry every ``"key":`` the documentation shows; the files named by ``--out``/``--plot``/``--png``/``--csv``
must exist afterwards. Not run: ``sphereplan serve`` (runs until stopped; tests/service/test_cli_serve.py and
test_http.py cover it), ``sphereplan bench`` (minutes; test_cli_bench*.py run it on small sets) and
lines that talk to a running server (``curl``, the load test); ``printf`` and ``python -c`` set-up lines run.

Also here: ``--help`` loads none of the heavy libraries (the tool's and every verb's), and the outputs of
the README's commands are ignored by git.
"""

from __future__ import annotations

import json
import os
import re
import shlex
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
DOCS = [REPO / "README.md", *sorted((REPO / "docs").glob("*.md"))]
NOT_RUN = {"serve", "bench"}


@dataclass(frozen=True)
class Example:
    doc: str
    line: int
    command: str
    output: str

    @property
    def id(self) -> str:
        return f"{self.doc}:{self.line}"


def _examples(path: Path) -> list[Example]:
    out: list[Example] = []
    lines = path.read_text().splitlines()
    fenced = False
    current: list[str] = []  # [command, output lines...]
    start = 0

    def flush() -> None:
        if current:
            out.append(Example(path.relative_to(REPO).as_posix(), start, current[0], "\n".join(current[1:])))
            current.clear()

    i = 0
    while i < len(lines):
        line = lines[i]
        if line.startswith("```"):
            flush()
            fenced = not fenced
        elif fenced and line.startswith("$ "):
            flush()
            start = i + 1
            command = line[2:]
            while command.rstrip().endswith("\\") and i + 1 < len(lines):
                i += 1
                command = command.rstrip()[:-1] + " " + lines[i].strip()
            current.append(command)
        elif fenced and current:
            current.append(line)
        elif not fenced and ".venv/bin/sphereplan " in line and line.startswith("    "):
            flush()
            command = line[line.index(".venv/bin/sphereplan ") + len(".venv/bin/") :]
            out.append(Example(path.relative_to(REPO).as_posix(), i + 1, command.split("  #")[0].strip(), ""))
        i += 1
    flush()
    return out


def _runnable(example: Example) -> bool:
    words = example.command.split()
    if "..." in example.command:
        return False  # a sketch, not a command
    if words[0] == "sphereplan":
        return not (len(words) > 1 and words[1] in NOT_RUN)
    return words[0] == "printf" or words[:2] == ["python", "-c"]  # set-up lines; curl etc. need a server


EXAMPLES = [e for doc in DOCS for e in _examples(doc)]
RUNNABLE = [e for e in EXAMPLES if _runnable(e)]


def test_the_docs_have_examples() -> None:
    docs_with_examples = {e.doc for e in RUNNABLE}
    assert {"README.md", "docs/getting-started.md", "docs/vpip.md", "docs/tensegrity.md"} <= docs_with_examples
    assert len(RUNNABLE) >= 15


def _shell_line(command: str) -> str:
    """The documented line with ``sphereplan`` and ``python`` as this checkout's (the shell runs pipes)."""
    cli = f"{shlex.quote(sys.executable)} -m service.cli"
    command = re.sub(r"(^|[|;&]\s*)sphereplan\b", lambda m: m.group(1) + cli, command)
    return re.sub(r"(^|[|;&]\s*)python3?\b", lambda m: m.group(1) + shlex.quote(sys.executable), command)


def _written_files(command: str) -> list[str]:
    words = shlex.split(command.split(" # ")[0]) if command.split()[0] == "sphereplan" else []
    return [words[k + 1] for k, w in enumerate(words[:-1]) if w in ("--out", "--plot", "--png", "--csv")]


@pytest.fixture(scope="module")
def scratch() -> dict[str, Path]:
    return {}


@pytest.mark.parametrize("example", RUNNABLE, ids=[e.id for e in RUNNABLE])
def test_documented_example_runs_as_shown(
    example: Example, scratch: dict[str, Path], tmp_path_factory: pytest.TempPathFactory
) -> None:
    folder = scratch.get(example.doc)
    if folder is None:  # one folder per document: its examples build on each other
        folder = scratch[example.doc] = tmp_path_factory.mktemp(Path(example.doc).stem)
        (folder / "maps").symlink_to(REPO / "maps")
    env = {**os.environ, "PYTHONPATH": str(REPO), "SPHEREPLAN_MAPS": str(REPO / "maps")}
    proc = subprocess.run(["bash", "-o", "pipefail", "-c", _shell_line(example.command)], cwd=folder, env=env,
                          capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, f"{example.id}: `{example.command}` exited {proc.returncode}:\n{proc.stderr[-2000:]}"
    if "--help" not in example.command:
        assert "Traceback" not in proc.stderr
    for name in _written_files(example.command):
        assert (folder / name).is_file(), f"{example.id}: `{example.command}` did not write {name}"
    shown = example.output.strip()
    if shown.startswith("{") and "| head" not in example.command:
        result = json.loads(proc.stdout)
        assert isinstance(result, dict)
        text = json.dumps(result)
        for key in re.findall(r'"([A-Za-z_][A-Za-z0-9_]*)":', shown):
            assert f'"{key}":' in text, f"{example.id}: documented key {key!r} missing from the output"
    elif shown.startswith("{"):  # a JSON document cut short by head: the keys shown, in the lines printed
        for key in re.findall(r'"([A-Za-z_][A-Za-z0-9_]*)":', shown):
            assert f'"{key}":' in proc.stdout, f"{example.id}: documented key {key!r} missing from the output"
    elif shown and not shown.startswith("→"):  # a table: its header line as shown
        header = next(line for line in shown.splitlines() if "maps in" not in line)
        said = (proc.stdout + proc.stderr).splitlines()
        assert any(header.split()[:4] == line.split()[:4] for line in said), f"{example.id}: {header!r} not said"


def test_help_loads_no_heavy_library() -> None:
    """``sphereplan --help`` and every verb's ``--help`` build the parsers without numpy, scipy, numba, ..."""
    code = (
        "import sys\n"
        "from service.cli import build_parser\n"
        "build_parser()\n"
        "heavy = {'numpy', 'scipy', 'numba', 'matplotlib', 'casadi', 'fastapi', 'zenoh', 'tqdm', 'trimesh'}\n"
        "print(sorted(heavy & {m.split('.')[0] for m in sys.modules}))\n"
    )
    proc = subprocess.run([sys.executable, "-c", code], cwd=REPO, capture_output=True, text=True, check=True)
    assert proc.stdout.strip() == "[]"


def test_choices_repeated_for_a_fast_help_match_the_planner() -> None:
    from planner.spherobot import request
    from planner.vpip import cascade, choices, circle
    from service.cli import reconfigure, vpip

    assert reconfigure.METHODS == request.METHODS
    # vpip's choices are not repeated: the CLI, the cascade and the circle runs share the light module's names
    for name in ("PLANTS", "DRIVERS"):
        assert getattr(vpip, name) is getattr(choices, name) is getattr(cascade, name) is getattr(circle, name)
    assert vpip.CONTACTS is choices.CONTACTS and vpip.GAIN_SETS is choices.GAIN_SETS


def test_readme_outputs_are_ignored_by_git() -> None:
    names = [n for e in _examples(REPO / "README.md") for n in _written_files(e.command)]
    assert names, "the README's plan command writes files"
    proc = subprocess.run(["git", "check-ignore", "--no-index", *names], cwd=REPO, capture_output=True, text=True)
    assert sorted(proc.stdout.split()) == sorted(names)
