"""Robot profiles: the physical data the planners, simulator and drivers share.

A profile is a TOML file (built-ins live in ``planner/robots/``; ``load_robot(path)`` reads a user's own).
It gives the shell radius, roll and speed limits, the footprint used for collision checking, and the
roll→curvature model that steers the sphere.

The footprint follows Nav2's ``footprint`` convention: a polygon ``[[x, y], ...]`` in the robot frame (x
forward, y left, metres), grown by ``footprint_padding_m`` the way Nav2 pads it (each vertex moved outward
by the padding in x and in y). Without a polygon the footprint is the ellipse of ``footprint_length_m`` ×
``footprint_width_m`` (a sphere's shell with its flanges), as a 16-gon drawn around it. ``reversible`` says
whether the robot rolls backwards as well as forwards (a sphere does); ``preferred_clearance_m`` is how
much room the planner tries to leave between the footprint and obstacles where there is room.

The roll→curvature models:

* ``kinematic`` — paper 001 eq. 1: yaw rate = v·tan φ / r, i.e. curvature κ(φ) = tan φ / r.
* ``calibrated`` — a table of measured (roll, turning radius) pairs (paper 000 §5: 5°, 10°, 15° →
  circle diameters 2.6, 2.0, 1.7 m). Curvature is interpolated monotonically (PCHIP) through (0, 0) and
  the measured points; beyond the last measured roll the curvature is held at the last measured value
  (the model does not extrapolate what was never measured). Negative rolls mirror positive ones.

Extra sections (``[vpip]``, ``[texplor]``, ``[spherobot]``, ``[sim]``) are kept verbatim in
``RobotProfile.extra`` for the modules that need them.
"""

from __future__ import annotations

import math
import tomllib
from collections.abc import Mapping
from dataclasses import dataclass, field
from functools import cached_property
from importlib import resources
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from planner.errors import NotFound, RobotProfileError

if TYPE_CHECKING:  # scipy.interpolate costs ~0.3 s to import: only when a roll table is interpolated
    from scipy.interpolate import PchipInterpolator

DEFAULT_ROBOT = "zju-60"
ELLIPSE_VERTICES = 16  # the default footprint: this many vertices around the ellipse
DEFAULT_PADDING_M = 0.01  # Nav2's footprint_padding default


def ellipse_footprint(length_m: float, width_m: float, n: int = ELLIPSE_VERTICES) -> tuple[tuple[float, float], ...]:
    """A convex n-gon containing the ellipse with axes ``length_m`` (x) × ``width_m`` (y), touching it at the
    middle of every edge (vertices at the ellipse's parametric angles, scaled by 1 / cos(π / n))."""
    scale = 1.0 / math.cos(math.pi / n)
    return tuple(
        (0.5 * length_m * scale * math.cos(2 * math.pi * (k + 0.5) / n),
         0.5 * width_m * scale * math.sin(2 * math.pi * (k + 0.5) / n))
        for k in range(n)
    )


def pad_footprint(points: np.ndarray, padding_m: float) -> np.ndarray:
    """Nav2's ``padFootprint``: every vertex moved outward by ``padding_m`` in x and in y (by its signs)."""
    return np.asarray(points, float) + np.sign(points) * padding_m


def _segments_cross(a: np.ndarray, b: np.ndarray, c: np.ndarray, d: np.ndarray) -> bool:
    def orient(p: np.ndarray, q: np.ndarray, r: np.ndarray) -> float:
        return float((q[0] - p[0]) * (r[1] - p[1]) - (q[1] - p[1]) * (r[0] - p[0]))

    return orient(a, b, c) * orient(a, b, d) < 0 and orient(c, d, a) * orient(c, d, b) < 0


@dataclass(frozen=True)
class RollModel:
    """Map between roll angle φ (rad, > 0 turns left) and signed path curvature κ (1/m).

    ``kind`` is ``"kinematic"`` (κ = tan φ / r) or ``"calibrated"`` (table of |φ| → turning radius).
    """

    kind: str
    radius_m: float
    table_roll_rad: tuple[float, ...] = ()
    table_radius_m: tuple[float, ...] = ()

    def __post_init__(self) -> None:
        if self.kind not in ("kinematic", "calibrated"):
            raise RobotProfileError("roll_model.kind", f"must be 'kinematic' or 'calibrated', got {self.kind!r}")
        if self.kind == "calibrated":
            rolls = np.asarray(self.table_roll_rad, dtype=float)
            radii = np.asarray(self.table_radius_m, dtype=float)
            if rolls.size < 1 or rolls.size != radii.size:
                raise RobotProfileError(
                    "roll_model.table", "needs at least one (roll, radius) pair and equal-length columns"
                )
            if np.any(rolls <= 0) or np.any(np.diff(rolls) <= 0):
                raise RobotProfileError("roll_model.table", "rolls must be positive and strictly increasing")
            if np.any(radii <= 0) or np.any(np.diff(1.0 / radii) <= 0):
                raise RobotProfileError(
                    "roll_model.table", "radii must be positive and shrink as roll grows (curvature increasing)"
                )

    @cached_property
    def _pchip(self) -> PchipInterpolator:
        """|φ| → κ through (0, 0) and the table; built once (the 100 Hz VPIP loop calls it often)."""
        from scipy.interpolate import PchipInterpolator

        rolls = np.concatenate([[0.0], np.asarray(self.table_roll_rad, float)])
        kappa = np.concatenate([[0.0], 1.0 / np.asarray(self.table_radius_m, float)])
        return PchipInterpolator(rolls, kappa, extrapolate=False)

    @cached_property
    def _inverse_grid(self) -> tuple[np.ndarray, np.ndarray]:
        """Dense monotone samples (κ, |φ|) for inverting the table by interpolation."""
        grid = np.linspace(0.0, self.max_table_roll_rad, 20001)
        return self._pchip(grid), grid

    @property
    def max_table_roll_rad(self) -> float:
        return float(self.table_roll_rad[-1]) if self.kind == "calibrated" else math.pi / 2

    def curvature(self, roll_rad: float | np.ndarray) -> np.ndarray | float:
        """Signed curvature κ (1/m) produced by holding roll ``roll_rad``."""
        phi = np.asarray(roll_rad, dtype=float)
        if self.kind == "kinematic":
            out = np.tan(phi) / self.radius_m
        else:
            mag = np.minimum(np.abs(phi), self.max_table_roll_rad)
            out = np.sign(phi) * self._pchip(mag)
        return float(out) if out.ndim == 0 else out

    def roll_for_curvature(self, curvature: float | np.ndarray) -> np.ndarray | float:
        """Inverse of :meth:`curvature`: the roll (rad) that produces curvature κ (1/m).

        For the calibrated model a curvature beyond the table's last point returns that point's roll.
        """
        k = np.asarray(curvature, dtype=float)
        if self.kind == "kinematic":
            out = np.arctan(k * self.radius_m)
        else:
            kap, grid = self._inverse_grid
            mag = np.interp(np.abs(k), kap, grid)
            out = np.sign(k) * mag
        return float(out) if out.ndim == 0 else out

    def turning_radius(self, roll_rad: float) -> float:
        """Turning radius (m) at roll ``roll_rad``; ``inf`` when upright."""
        k = abs(float(self.curvature(roll_rad)))
        return math.inf if k == 0 else 1.0 / k


@dataclass(frozen=True)
class RobotProfile:
    """Everything the planners need to know about one robot (SI units, radians)."""

    name: str
    radius_m: float
    max_roll_rad: float
    max_roll_rate_rad_s: float
    roll_time_constant_s: float
    max_speed_m_s: float
    max_accel_m_s2: float
    footprint_length_m: float
    footprint_width_m: float
    roll_model: RollModel
    description: str = ""
    extra: Mapping[str, Any] = field(default_factory=dict)
    footprint: tuple[tuple[float, float], ...] = ()
    footprint_padding_m: float = DEFAULT_PADDING_M
    reversible: bool = True
    preferred_clearance_m: float = 0.0

    @cached_property
    def footprint_polygon(self) -> np.ndarray:
        """The padded footprint polygon (n, 2) in the robot frame (x forward, y left), metres: what collides."""
        base = self.footprint or ellipse_footprint(self.footprint_length_m, self.footprint_width_m)
        return pad_footprint(np.array(base, float), self.footprint_padding_m)

    @cached_property
    def max_curvature(self) -> float:
        """Largest curvature (1/m) the robot can hold, at ``max_roll_rad`` (the profile is frozen: worked out once,
        it was asked for a few times a plan)."""
        return abs(float(self.roll_model.curvature(self.max_roll_rad)))

    @cached_property
    def min_turning_radius_m(self) -> float:
        return 1.0 / self.max_curvature

    def to_json(self) -> dict[str, Any]:
        """The profile as the result JSON carries it (docs/contracts.md: ``robot``)."""
        model: dict[str, Any] = {"kind": self.roll_model.kind}
        if self.roll_model.kind == "calibrated":
            model["roll_rad"] = list(self.roll_model.table_roll_rad)
            model["radius_m"] = list(self.roll_model.table_radius_m)
        return {
            "name": self.name,
            "radius_m": self.radius_m,
            "max_roll_rad": self.max_roll_rad,
            "max_roll_rate_rad_s": self.max_roll_rate_rad_s,
            "max_speed_m_s": self.max_speed_m_s,
            "footprint_length_m": self.footprint_length_m,
            "footprint_width_m": self.footprint_width_m,
            "footprint": [[round(float(x), 6), round(float(y), 6)] for x, y in self.footprint_polygon],
            "footprint_padding_m": self.footprint_padding_m,
            "reversible": self.reversible,
            "preferred_clearance_m": self.preferred_clearance_m,
            "min_turning_radius_m": self.min_turning_radius_m,
            "roll_model": model,
        }


def _positive(data: Mapping[str, Any], key: str, where: str) -> float:
    if key not in data:
        raise RobotProfileError(f"{where}{key}", "is required")
    value = data[key]
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise RobotProfileError(f"{where}{key}", f"must be a number, got {value!r}")
    value = float(value)
    if not math.isfinite(value) or value <= 0:
        raise RobotProfileError(f"{where}{key}", f"must be a finite number > 0, got {value!r}")
    return value


def _non_negative(data: Mapping[str, Any], key: str, default: float) -> float:
    value = data.get(key, default)
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value) or value < 0:
        raise RobotProfileError(key, f"must be a finite number ≥ 0, got {value!r}")
    return float(value)


def _polygon(value: Any) -> tuple[tuple[float, float], ...]:
    """A footprint polygon from TOML: ≥ 3 finite [x, y] points, non-zero area, edges not crossing."""
    if not isinstance(value, list) or len(value) < 3:
        raise RobotProfileError("footprint", "must be a list of at least three [x, y] points (metres)")
    pts: list[tuple[float, float]] = []
    for i, pt in enumerate(value):
        if (not isinstance(pt, list) or len(pt) != 2
                or not all(isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v) for v in pt)):
            raise RobotProfileError(f"footprint[{i}]", f"must be two finite numbers [x, y], got {pt!r}")
        pts.append((float(pt[0]), float(pt[1])))
    arr = np.array(pts)
    area = 0.5 * float(np.sum(arr[:, 0] * np.roll(arr[:, 1], -1) - np.roll(arr[:, 0], -1) * arr[:, 1]))
    if abs(area) < 1e-6:
        raise RobotProfileError("footprint", "encloses no area")
    n = len(arr)
    for i in range(n):
        for j in range(i + 2, n):
            if i == 0 and j == n - 1:
                continue
            if _segments_cross(arr[i], arr[(i + 1) % n], arr[j], arr[(j + 1) % n]):
                raise RobotProfileError("footprint", f"edges {i} and {j} cross (the polygon must be simple)")
    if not (arr.min(axis=0) < 0).all() or not (arr.max(axis=0) > 0).all():
        raise RobotProfileError("footprint", "must surround the robot's centre (0, 0)")
    return tuple(pts)


def profile_from_dict(data: Mapping[str, Any], default_name: str = "custom") -> RobotProfile:
    """Build a :class:`RobotProfile` from parsed TOML. Angles in the file are in degrees (``*_deg``)."""
    name = str(data.get("name", default_name))
    radius = _positive(data, "radius_m", "")
    max_roll = math.radians(_positive(data, "max_roll_deg", ""))
    if max_roll >= math.radians(60):
        raise RobotProfileError("max_roll_deg", "must be below 60 degrees")
    model_data = data.get("roll_model", {"kind": "kinematic"})
    if not isinstance(model_data, Mapping):
        raise RobotProfileError("roll_model", "must be a table")
    kind = str(model_data.get("kind", "kinematic"))
    if kind == "calibrated":
        rolls = model_data.get("roll_deg")
        diam = model_data.get("diameter_m")
        if not isinstance(rolls, list) or not isinstance(diam, list):
            raise RobotProfileError("roll_model", "a calibrated model needs lists roll_deg and diameter_m")
        model = RollModel(
            kind,
            radius,
            tuple(math.radians(float(a)) for a in rolls),
            tuple(float(d) / 2.0 for d in diam),
        )
    else:
        model = RollModel(kind, radius)
    known = {
        "name", "description", "radius_m", "max_roll_deg", "max_roll_rate_deg_s", "roll_time_constant_s",
        "max_speed_m_s", "max_accel_m_s2", "footprint_length_m", "footprint_width_m", "roll_model",
        "footprint", "footprint_padding_m", "reversible", "preferred_clearance_m",
    }
    polygon = _polygon(data["footprint"]) if "footprint" in data else ()
    if polygon:  # the extents follow the polygon (Nav2 gives only the polygon)
        arr = np.array(polygon)
        length = 2.0 * float(np.abs(arr[:, 0]).max())
        width = 2.0 * float(np.abs(arr[:, 1]).max())
    else:
        length = _positive(data, "footprint_length_m", "")
        width = _positive(data, "footprint_width_m", "")
    reversible = data.get("reversible", True)
    if not isinstance(reversible, bool):
        raise RobotProfileError("reversible", f"must be true or false, got {reversible!r}")
    extra = {k: v for k, v in data.items() if k not in known}
    for key, value in extra.items():
        if not isinstance(value, Mapping):
            raise RobotProfileError(key, "unknown field (extra sections must be tables such as [vpip])")
    return RobotProfile(
        name=name,
        radius_m=radius,
        max_roll_rad=max_roll,
        max_roll_rate_rad_s=math.radians(_positive(data, "max_roll_rate_deg_s", "")),
        roll_time_constant_s=_positive(data, "roll_time_constant_s", ""),
        max_speed_m_s=_positive(data, "max_speed_m_s", ""),
        max_accel_m_s2=_positive(data, "max_accel_m_s2", ""),
        footprint_length_m=length,
        footprint_width_m=width,
        roll_model=model,
        description=str(data.get("description", "")),
        extra=extra,
        footprint=polygon,
        footprint_padding_m=_non_negative(data, "footprint_padding_m", DEFAULT_PADDING_M),
        reversible=reversible,
        preferred_clearance_m=_non_negative(data, "preferred_clearance_m", 0.0),
    )


def builtin_robots() -> list[str]:
    """Names of the profiles shipped with sphereplan."""
    folder = resources.files("planner") / "robots"
    return sorted(p.name[:-5] for p in folder.iterdir() if p.name.endswith(".toml"))


def load_robot(name_or_path: str | Path | None = None) -> RobotProfile:
    """Load a built-in profile by name (``zju-60``) or a user's TOML file by path.

    Raises :class:`NotFound` for an unknown name and :class:`RobotProfileError` for a bad file.
    """
    spec = DEFAULT_ROBOT if name_or_path is None else str(name_or_path)
    path = Path(spec)
    if spec.endswith(".toml") or path.is_file():
        if not path.is_file():
            raise NotFound("robot", f"profile file {spec} does not exist")
        text = path.read_text()
        default_name = path.stem
    else:
        if spec not in builtin_robots():
            raise NotFound("robot", f"unknown robot {spec!r}; built-in: {', '.join(builtin_robots())}")
        text = (resources.files("planner") / "robots" / f"{spec}.toml").read_text()
        default_name = spec
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise RobotProfileError("robot", f"{spec} is not valid TOML: {exc}") from exc
    return profile_from_dict(data, default_name)
