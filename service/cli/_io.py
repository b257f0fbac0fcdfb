"""Helpers every CLI verb shares: JSON output and finite-number argument types."""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path
from typing import Any


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
