"""Helpers every CLI verb shares: JSON output, finite-number and angle argument types, progress on stderr."""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from collections.abc import Sequence
from pathlib import Path
from types import TracebackType
from typing import Any, TextIO

from planner.errors import InvalidInput


def finite_float(text: str) -> float:
    """argparse type: a finite float (rejects nan/inf with a clear message)."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"{text!r} is not a finite number")
    return value


def positive_float(text: str) -> float:
    value = finite_float(text)
    if value <= 0:
        raise argparse.ArgumentTypeError(f"{text!r} must be > 0")
    return value


def add_degrees_flag(parser: argparse.ArgumentParser) -> None:
    """``--degrees``: the one spelling, on every command that reads an angle (the output stays radians)."""
    parser.add_argument(
        "--degrees", action="store_true", help="input angles are in degrees (output stays radians)"
    )


def angle(args: argparse.Namespace, value: float) -> float:
    """An angle as typed, in radians (``--degrees`` converts)."""
    return math.radians(value) if getattr(args, "degrees", False) else value


#: -1 with ``-q`` (errors only), 0 by default (progress), 1 with ``-v`` (and log INFO), 2 with ``-vv`` (DEBUG)
_verbosity = 0


def set_verbosity(level: int) -> None:
    global _verbosity
    _verbosity = level


def say(verb: str, message: str) -> None:
    """A one-line summary on stderr (``sphereplan VERB: message``), unless ``-q``."""
    if _verbosity >= 0:
        sys.stderr.write(f"sphereplan {verb}: {message}\n")


class Stages:
    """Progress through the named stages of one command, always on stderr (stdout may carry JSON).

    On a terminal a tqdm bar (stage i of n, the stage's name, elapsed time); otherwise one line per stage,
    ``sphereplan VERB: [i/n] stage`` and, with ``-v``, how long the previous stage took. ``-q`` silences it.
    Use as a context manager and call ``stages.start("name")`` as each stage begins.
    """

    def __init__(self, verb: str, names: Sequence[str], stream: TextIO | None = None) -> None:
        self.verb = verb
        self.names = list(names)
        self.stream = stream if stream is not None else sys.stderr
        self.index = 0
        self.started = time.perf_counter()
        self._bar: Any = None
        self._last: tuple[str, float] | None = None
        if _verbosity >= 0 and self.stream.isatty():
            from tqdm import tqdm

            self._bar = tqdm(total=len(self.names), file=self.stream, desc=verb, leave=False,
                             bar_format="{desc}: {n_fmt}/{total_fmt} {postfix} [{elapsed}]")

    def start(self, name: str) -> None:
        """Stage ``name`` begins (it need not be in ``names``: optional stages may be skipped)."""
        now = time.perf_counter()
        if name in self.names:
            self.index = self.names.index(name) + 1
        if self._bar is not None:
            self._bar.n = self.index - 1
            self._bar.set_postfix_str(name)
        elif _verbosity >= 0:
            took = f" (previous stage {now - self._last[1]:.2f} s)" if self._last and _verbosity >= 1 else ""
            self.stream.write(f"sphereplan {self.verb}: [{self.index}/{len(self.names)}] {name}{took}\n")
            self.stream.flush()
        self._last = (name, now)

    def __enter__(self) -> Stages:
        return self

    def __exit__(self, exc_type: type[BaseException] | None, exc: BaseException | None,
                 tb: TracebackType | None) -> None:
        if self._bar is not None:
            self._bar.n = len(self.names) if exc is None else self._bar.n
            self._bar.close()
        elif _verbosity >= 1 and exc is None:
            self.stream.write(f"sphereplan {self.verb}: done in {time.perf_counter() - self.started:.2f} s\n")


def emit_json(result: Any, out: str | Path | None) -> None:
    """Print ``result`` as JSON on stdout, or write it to ``out`` when given."""
    text = json.dumps(result, indent=2, allow_nan=False)
    if out:
        Path(out).write_text(text + "\n")
    else:
        sys.stdout.write(text + "\n")


def read_json_file(path: str | Path, field: str) -> Any:
    """Parse a JSON file the user named with option ``field``; errors name the field (exit 2)."""
    p = Path(path)
    if not p.is_file():
        raise InvalidInput(field, f"file {p} does not exist")
    try:
        return json.loads(p.read_text())
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise InvalidInput(field, f"{p} is not valid JSON: {exc}") from None
