"""Helpers every CLI verb shares: JSON output and finite-number argument types."""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path
from typing import Any

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
