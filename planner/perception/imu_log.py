"""An IMU attitude log for batch stabilisation: a CSV of ``time, roll, pitch`` rows, sampled at frame times.

The file has three columns (an optional header line naming them ``time,roll,pitch`` in any case): time in
seconds, increasing; roll and pitch the camera's REP-103 attitude in radians (degrees with ``degrees=True``).
Frames are given in file-name order; frame i is taken at ``t0 + i / fps`` (t0 the log's first time) and its angles
are interpolated linearly in the log, or, without ``fps``, row i belongs to frame i (as many rows as frames).
"""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from planner.errors import InvalidInput
from planner.perception.mount import check_angle

COLUMNS = ("time", "roll", "pitch")


@dataclass(frozen=True)
class ImuLog:
    """Times (N,) s, strictly increasing; roll and pitch (N,) rad, REP-103."""

    time_s: np.ndarray
    roll_rad: np.ndarray
    pitch_rad: np.ndarray

    def at_frames(self, count: int, fps: float | None, field: str = "--imu") -> tuple[np.ndarray, np.ndarray]:
        """(roll, pitch) (count,) rad of ``count`` frames (see the module text)."""
        if fps is None:
            if len(self.time_s) != count:
                raise InvalidInput(field, f"has {len(self.time_s)} rows for {count} frames; give one row per frame "
                                          "or --fps to interpolate")
            return self.roll_rad.copy(), self.pitch_rad.copy()
        t = self.time_s[0] + np.arange(count) / fps
        if count and t[-1] > self.time_s[-1] + 1e-9:
            raise InvalidInput(field, f"ends at {self.time_s[-1]:g} s, before the last frame at {t[-1]:g} s")
        return np.interp(t, self.time_s, self.roll_rad), np.interp(t, self.time_s, self.pitch_rad)


def read_imu_csv(path: str | Path, degrees: bool = False, field: str = "--imu") -> ImuLog:
    """Read the log; a missing file, a short or non-numeric row, a non-finite value, time that does not increase
    or an angle outside [−2π, 2π] rad is :class:`InvalidInput` naming ``field`` and the row."""
    p = Path(path)
    if not p.is_file():
        raise InvalidInput(field, f"file {p} does not exist")
    try:
        lines = list(csv.reader(p.read_text().splitlines()))
    except (UnicodeDecodeError, csv.Error) as exc:
        raise InvalidInput(field, f"{p} is not a readable CSV: {exc}") from None
    rows: list[tuple[float, float, float]] = []
    for number, line in enumerate(lines, start=1):
        cells = [c.strip() for c in line]
        if not any(cells):
            continue
        if number == 1 and [c.lower() for c in cells[:3]] == list(COLUMNS):
            continue
        if len(cells) < 3:
            raise InvalidInput(field, f"row {number} has {len(cells)} columns; need time, roll, pitch")
        values = []
        for name, cell in zip(COLUMNS, cells[:3], strict=True):
            try:
                value = float(cell)
            except ValueError:
                raise InvalidInput(field, f"row {number}: {name} {cell!r} is not a number") from None
            if not math.isfinite(value):
                raise InvalidInput(field, f"row {number}: {name} is {cell!r}, not a finite number")
            if name != "time":
                value = math.radians(value) if degrees else value
                check_angle(value, f"{field} row {number} {name}")
            values.append(value)
        rows.append((values[0], values[1], values[2]))
    if not rows:
        raise InvalidInput(field, f"{p} holds no rows")
    a = np.array(rows)
    if np.any(np.diff(a[:, 0]) <= 0):
        raise InvalidInput(field, "time must increase from row to row")
    return ImuLog(a[:, 0], a[:, 1], a[:, 2])


#: image files a frames folder may hold
FRAME_SUFFIXES = (".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff")


def list_frames(folder: str | Path, field: str = "--frames") -> list[Path]:
    """The image files of ``folder`` in name order; none, or no such folder, is InvalidInput(field)."""
    p = Path(folder)
    if not p.is_dir():
        raise InvalidInput(field, f"{p} is not a folder")
    frames = sorted(f for f in p.iterdir() if f.is_file() and f.suffix.lower() in FRAME_SUFFIXES)
    if not frames:
        raise InvalidInput(field, f"{p} holds no image files ({', '.join(FRAME_SUFFIXES)})")
    return frames
