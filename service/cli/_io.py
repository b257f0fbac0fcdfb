"""Helpers every CLI verb shares: JSON output and finite-number argument types."""

from __future__ import annotations

import argparse
import json
import math
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

from planner.errors import InvalidInput
from planner.occupancy import OccupancyGrid


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


def check_output(path: str | Path | None, field: str, formats: set[str] | None = None) -> None:
    """Before any work: ``path`` (an option naming a file to write) must be a file in an existing folder,
    with one of ``formats`` as its extension when given; else :class:`InvalidInput` naming ``field``."""
    if not path:
        return
    p = Path(path)
    if p.is_dir():
        raise InvalidInput(field, f"{p} is a folder; give a file name")
    if not p.parent.is_dir():
        raise InvalidInput(field, f"folder {p.parent} does not exist")
    if formats is not None and p.suffix.lower().lstrip(".") not in formats:
        raise InvalidInput(field, f"unsupported image format {p.suffix or '(none)'!r}; use one of "
                                  f"{', '.join(sorted(formats))}")


def plot_formats() -> set[str]:
    """The image formats matplotlib can write (the extensions a ``--plot`` file may have)."""
    from matplotlib.backend_bases import FigureCanvasBase

    return set(FigureCanvasBase.get_supported_filetypes())


def write_file(path: str | Path, field: str, write: Any) -> None:
    """Call ``write()`` (which writes ``path``), turning a file system refusal into bad input naming ``field``."""
    try:
        write()
    except OSError as exc:
        raise InvalidInput(field, f"cannot write {path}: {exc.strerror or exc}") from None


def emit_json(result: Any, out: str | Path | None, field: str = "--out") -> None:
    """Print ``result`` as JSON on stdout, or write it to ``out`` when given (a refusal is bad input
    naming ``field``)."""
    text = json.dumps(result, indent=2, allow_nan=False)
    if out:
        write_file(out, field, lambda: Path(out).write_text(text + "\n"))
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
    except RecursionError:
        raise InvalidInput(field, f"{p} is nested too deeply") from None


def is_mcap_out(out: str | Path | None) -> bool:
    return out is not None and str(out).lower().endswith(".mcap")


def emit_result(result: Any, out: str | Path | None, write_mcap: Callable[[str], None]) -> None:
    """``--out``: a name ending in ``.mcap`` gets ROS 2 messages (``write_mcap(out)``) and the JSON goes to
    stdout; any other name gets the JSON; no name prints the JSON."""
    if out is not None and is_mcap_out(out):
        write_file(out, "--out", lambda: write_mcap(str(out)))
        emit_json(result, None)
    else:
        emit_json(result, out)


def is_bag(path: str | Path) -> bool:
    """An MCAP file or a rosbag2 folder (holds ``metadata.yaml``)."""
    p = Path(path)
    return p.suffix.lower() == ".mcap" or (p.is_dir() and (p / "metadata.yaml").is_file())


def read_bag_map(path: str, topic: str | None) -> OccupancyGrid:
    """The last ``nav_msgs/OccupancyGrid`` on ``topic`` (default ``/map``) of an MCAP file / rosbag2 folder."""
    from service.ros import MAP_TOPIC, read_map_from_bag

    return read_map_from_bag(path, topic or MAP_TOPIC)


def read_map_arg(path: str, topic: str | None, robot: Any = None) -> OccupancyGrid:
    """``--map`` of a verb: a map_server YAML or mesh (``planner.maps.load.load_any``), or with an MCAP
    file / rosbag2 folder the last ``nav_msgs/OccupancyGrid`` on ``--map-topic`` (default ``/map``)."""
    if not Path(path).exists():
        raise InvalidInput("--map", f"{path} does not exist")
    if is_bag(path):
        return read_bag_map(path, topic)
    if topic is not None:
        raise InvalidInput("--map-topic", "only applies to an MCAP file or a rosbag2 folder given as --map")
    from service.grids import read_map

    return read_map(path, robot, "--map")
