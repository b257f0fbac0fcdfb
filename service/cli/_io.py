"""Helpers every CLI verb shares: JSON output, finite-number and angle argument types, progress on stderr."""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from types import TracebackType
from typing import TYPE_CHECKING, Any, TextIO

from planner.errors import InvalidInput

if TYPE_CHECKING:
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


def add_degrees_flag(parser: argparse.ArgumentParser) -> None:
    """``--degrees``: the one spelling, on every command that reads an angle (the output stays radians).

    The rule: options whose names say their unit (``--roll-deg``) are in that unit whatever ``--degrees`` says;
    ``--degrees`` converts the others. Either way an angle must lie in [−2π, 2π] rad (±360°)."""
    parser.add_argument(
        "--degrees", action="store_true",
        help="input angles are in degrees (output stays radians; options named --...-deg are degrees anyway)"
    )


def angle(args: argparse.Namespace, value: float, field: str) -> float:
    """An angle as typed, in radians (``--degrees`` converts); outside [−2π, 2π] rad it is bad input naming
    ``field`` and suggesting ``--degrees`` (:func:`planner.angles.check_angle`, the rule of every door)."""
    from planner.angles import check_angle

    rad = math.radians(value) if getattr(args, "degrees", False) else value
    return check_angle(field, rad, "--degrees")


def angle_deg(value: float, field: str) -> float:
    """An option that is in degrees by its name (``--roll-deg``), checked by the same rule (±360°); returns
    the degrees unchanged."""
    from planner.angles import check_angle

    check_angle(field, math.radians(value), f"{field} (already degrees; within ±360)")
    return value


#: -1 with ``-q`` (errors only), 0 by default (progress), 1 with ``-v`` (and log INFO), 2 with ``-vv`` (DEBUG)
_verbosity = 0


def set_verbosity(level: int) -> None:
    global _verbosity
    _verbosity = level


def quiet() -> bool:
    """Whether ``-q`` was given (before or after the verb): no progress at all."""
    return _verbosity < 0


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


def make_folder(folder: str | Path, field: str) -> Path:
    """``folder`` (an output folder a user named), created with its parents if missing; a file in the way or a
    refusal of the file system is bad input naming ``field``."""
    p = Path(folder)
    try:
        p.mkdir(parents=True, exist_ok=True)
    except FileExistsError:
        raise InvalidInput(field, f"{p} (or a folder above it) is a file, not a folder") from None
    except OSError as exc:
        raise InvalidInput(field, f"cannot create folder {p}: {exc.strerror or exc}") from None
    return p


def check_output(path: str | Path | None, field: str, formats: set[str] | None = None) -> None:
    """Before any work: ``path`` (an option naming a file to write) must be a file name, with one of ``formats``
    as its extension when given; its folder is created if missing (:func:`make_folder`); else
    :class:`InvalidInput` naming ``field``."""
    if not path:
        return
    p = Path(path)
    if p.is_dir():
        raise InvalidInput(field, f"{p} is a folder; give a file name")
    if formats is not None and p.suffix.lower().lstrip(".") not in formats:
        raise InvalidInput(field, f"unsupported image format {p.suffix or '(none)'!r}; use one of "
                                  f"{', '.join(sorted(formats))}")
    make_folder(p.parent, field)


#: the options, on any verb, that name a file to write (their folders are created) or a folder to write into
OUTPUT_FILES = {"out": "--out", "plot": "--plot", "csv": "--csv", "png": "--png"}
OUTPUT_FOLDERS = {"out_dir": "--out-dir"}


def make_output_folders(args: argparse.Namespace) -> None:
    """Create the folders every output option of a verb names (``--out runs/a.json`` makes ``runs/``), so no verb
    fails after its work for want of a folder; a file in the way is bad input naming the option."""
    for attr, field in OUTPUT_FILES.items():
        value = getattr(args, attr, None)
        if isinstance(value, str) and value and not Path(value).is_dir():
            make_folder(Path(value).parent, field)
    for attr, field in OUTPUT_FOLDERS.items():
        value = getattr(args, attr, None)
        if isinstance(value, str) and value:
            make_folder(value, field)


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


def map_path(text: str, field: str = "--map") -> str:
    """What a ``--map`` names, as a path: a file or folder that exists (relative to the current folder), else a
    shipped map by name (``garage``, as HTTP and docs/maps.md name them), else a shipped file by its path in the
    repository (``maps/garage.yaml`` from any folder); otherwise bad input naming ``field``."""
    if Path(text).exists():
        return text
    from planner.errors import NotFound
    from planner.maps.catalogue import default_maps_dir, map_files

    try:
        folder = default_maps_dir()
    except NotFound:
        raise InvalidInput(field, f"{text} does not exist") from None
    index = map_files(folder)
    if text in index:
        return str(index[text])
    shipped = folder.parent / text
    if not Path(text).is_absolute() and shipped.exists():
        return str(shipped)
    names = ", ".join(sorted(index)) or "none"
    raise InvalidInput(field, f"{text} does not exist, and it is not a shipped map (names: {names})")


def read_map_arg(path: str, topic: str | None, robot: Any = None) -> OccupancyGrid:
    """``--map`` of a verb (:func:`map_path`: a file, a shipped map's name or a shipped file from any folder): a
    map_server YAML or mesh (``planner.maps.load.load_any``), or with an MCAP file / rosbag2 folder the last
    ``nav_msgs/OccupancyGrid`` on ``--map-topic`` (default ``/map``)."""
    path = map_path(path)
    if is_bag(path):
        return read_bag_map(path, topic)
    if topic is not None:
        raise InvalidInput("--map-topic", "only applies to an MCAP file or a rosbag2 folder given as --map")
    from service.grids import read_map

    return read_map(path, robot, "--map")


def seed_int(text: str) -> int:
    """argparse type of a ``--seed``: an integer ≥ 0."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not an integer") from None
    if value < 0:
        raise argparse.ArgumentTypeError(f"{text!r} must be >= 0")
    return value
