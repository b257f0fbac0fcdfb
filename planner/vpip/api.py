"""The VPIP capability as plain functions returning JSON-ready dicts: exactly what ``sphereplan vpip`` prints.

The CLI (``service/cli/vpip.py``) and the HTTP/Zenoh services call these; all angles are radians,
lengths metres, and errors are :mod:`planner.errors` exceptions naming the bad field.
"""

from __future__ import annotations

import csv
import io
import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from planner.errors import InvalidInput, RobotProfileError
from planner.robot import RobotProfile, RollModel, load_robot
from planner.termination import Termination
from planner.vpip.cascade import rod_params, run_schedule
from planner.vpip.circle import run_circle
from planner.vpip.rods import rod_lengths
from planner.vpip.settings import setting_names, with_settings


def _finite(name: str, value: float) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(float(value)):
        raise InvalidInput(name, f"must be a finite number, got {value!r}")
    return float(value)


def _none_if_nan(value: float) -> float | None:
    return None if not math.isfinite(value) else float(value)


def rods_report(
    phi_vpip_rad: float,
    theta_vpip_rad: float,
    roll_rad: float,
    pitch_phase_rad: float = 0.0,
    robot: str | RobotProfile = "daedalus",
) -> dict[str, Any]:
    """Eq. 18 rod lengths for one plane, roll and pitch phase (``sphereplan vpip rods``)."""
    profile = robot if isinstance(robot, RobotProfile) else load_robot(robot)
    params = rod_params(profile)
    phi = _finite("phi_vpip", phi_vpip_rad)
    theta = _finite("theta_vpip", theta_vpip_rad)
    roll = _finite("roll", roll_rad)
    phase = _finite("pitch_phase", pitch_phase_rad)
    cmd = rod_lengths(params, phi, theta, roll, phase)
    n = params.rods_per_side
    rods = [
        {
            "index": i,
            "side": "left" if i < n else "right",
            "zeta_rad": float(cmd.zeta_rad[i]),
            "length_m": float(cmd.length_m[i]),
            "raw_length_m": _none_if_nan(float(cmd.raw_length_m[i])),
            "active": bool(cmd.active[i]),
            "clamped": {-1: "retracted", 1: "extended", 0: None}[int(cmd.clamped[i])],
        }
        for i in range(params.n_rods)
    ]
    return {
        "robot": profile.name,
        "params": {"r_m": params.r_m, "r_s": params.r_s, "l_max": params.l_max, "d_m_s": params.d_m_s},
        "inputs": {
            "phi_vpip_rad": phi,
            "theta_vpip_rad": theta,
            "roll_rad": roll,
            "pitch_phase_rad": phase,
        },
        "rods": rods,
    }


def _model_name(model: RollModel) -> str:
    return "calibrated table" if model.kind == "calibrated" else "kinematic R = r / tan(roll)"


def radius_report(roll_rad: float, robot: str | RobotProfile = "daedalus") -> dict[str, Any]:
    """Turning radius held at roll ``roll_rad`` (``sphereplan vpip radius``); null when upright."""
    profile = robot if isinstance(robot, RobotProfile) else load_robot(robot)
    roll = _finite("roll", roll_rad)
    if abs(roll) >= 0.5 * math.pi:
        raise InvalidInput("roll", "must be strictly between -90 and 90 degrees")
    model = profile.roll_model
    k = float(model.curvature(roll))
    radius = model.turning_radius(roll)
    return {
        "robot": profile.name,
        "model": _model_name(model),
        "roll_rad": roll,
        "curvature_1_m": k,
        "radius_m": None if math.isinf(radius) else radius,
        "beyond_table": model.kind == "calibrated" and abs(roll) > model.max_table_roll_rad,
    }


def roll_report(radius_m: float, robot: str | RobotProfile = "daedalus", left: bool = True) -> dict[str, Any]:
    """Roll that holds turning radius ``radius_m`` (``sphereplan vpip roll``); > 0 for a left turn.

    A radius tighter than the model can produce returns the largest roll it knows and
    ``achievable: false`` with the radius actually reached.
    """
    profile = robot if isinstance(robot, RobotProfile) else load_robot(robot)
    radius = _finite("radius", radius_m)
    if radius <= 0:
        raise InvalidInput("radius", f"must be > 0, got {radius}")
    model = profile.roll_model
    k = (1.0 if left else -1.0) / radius
    roll = float(model.roll_for_curvature(k))
    reached = model.turning_radius(roll)
    return {
        "robot": profile.name,
        "model": _model_name(model),
        "radius_m": radius,
        "roll_rad": roll,
        "roll_deg": math.degrees(roll),
        "achievable": bool(abs(reached - radius) <= 1e-6 * radius),
        "achieved_radius_m": reached,
        "within_max_roll": abs(roll) <= profile.max_roll_rad + 1e-12,
    }


def parse_runs_csv(text: str) -> tuple[list[float], list[float]]:
    """Rows of measured runs: header ``roll_deg,diameter_m`` (or ``roll_rad``/``radius_m``)."""
    reader = csv.DictReader(io.StringIO(text))
    fields = [f.strip() for f in (reader.fieldnames or [])]
    roll_key = next((f for f in ("roll_deg", "roll_rad") if f in fields), None)
    size_key = next((f for f in ("diameter_m", "radius_m") if f in fields), None)
    if roll_key is None or size_key is None:
        raise InvalidInput(
            "runs", "CSV needs a header with roll_deg (or roll_rad) and diameter_m (or radius_m)"
        )
    rolls: list[float] = []
    radii: list[float] = []
    for line, row in enumerate(reader, start=2):
        row = {k.strip(): v for k, v in row.items() if k is not None}
        try:
            r = float(row[roll_key])
            size = float(row[size_key])
        except (TypeError, ValueError):
            raise InvalidInput(f"runs line {line}", f"{roll_key} and {size_key} must be numbers") from None
        if not (math.isfinite(r) and math.isfinite(size)) or r <= 0 or size <= 0:
            raise InvalidInput(
                f"runs line {line}", "roll and size must be finite and > 0 (left/right runs: use |roll|)"
            )
        rolls.append(math.radians(r) if roll_key == "roll_deg" else r)
        radii.append(size / 2.0 if size_key == "diameter_m" else size)
    if not rolls:
        raise InvalidInput("runs", "no runs in the CSV")
    return rolls, radii


def _fit_roll_table(
    rolls: list[float], radii: list[float], profile: RobotProfile, field: str = "runs"
) -> dict[str, Any]:
    """Roll model from runs (roll rad, radius m): runs at one roll are averaged in curvature."""
    groups: dict[float, list[float]] = {}  # keyed by roll in degrees (rounded to 1e-6 deg)
    for r, rad in zip(rolls, radii, strict=True):
        groups.setdefault(round(math.degrees(r), 6), []).append(1.0 / rad)
    table_deg = sorted(groups)
    table_roll = [math.radians(d) for d in table_deg]
    table_radius = [1.0 / float(np.mean(groups[d])) for d in table_deg]
    try:
        model = RollModel("calibrated", profile.radius_m, tuple(table_roll), tuple(table_radius))
    except RobotProfileError as exc:
        raise InvalidInput(field, f"cannot make a roll model from these runs: {exc.msg}") from None
    fit = [
        {
            "roll_deg": d,
            "runs": len(groups[d]),
            "diameter_m": 2.0 * rad,
            "kinematic_diameter_m": 2.0 * profile.radius_m / math.tan(r),
        }
        for d, r, rad in zip(table_deg, table_roll, table_radius, strict=True)
    ]
    return {
        "robot": profile.name,
        "roll_model": {
            "kind": "calibrated",
            "roll_deg": table_deg,
            "diameter_m": [2.0 * r for r in table_radius],
        },
        "table": fit,
        "outside_range": "curvature is interpolated (PCHIP) from (0, 0) to the first run and held at "
        "the last run's value beyond it",
        "min_turning_radius_m": model.turning_radius(model.max_table_roll_rad),
    }


def calibrate_report(runs_csv_text: str, robot: str | RobotProfile = "daedalus") -> dict[str, Any]:
    """Fit a calibrated roll model from measured runs (``sphereplan vpip calibrate --runs``).

    Runs at the same roll are averaged in curvature; the table is (roll, mean radius) sorted by roll,
    interpolated by :class:`~planner.robot.RollModel` (PCHIP through (0, 0), held beyond the last roll).
    """
    profile = robot if isinstance(robot, RobotProfile) else load_robot(robot)
    rolls, radii = parse_runs_csv(runs_csv_text)
    return {**_fit_roll_table(rolls, radii, profile), "source": "measured runs (CSV)"}


def calibrate_from_circles(
    circles: list[Mapping[str, Any]], robot: str | RobotProfile = "daedalus"
) -> dict[str, Any]:
    """Fit the roll model from circle runs (:func:`circle_report` results, or their ``summary``).

    Each run contributes (|desired roll|, fitted diameter): the table maps the roll the cascade *asks*
    for to the circle the plant then rolls, which is what a planner needs. Runs that did not turn
    enough to fit a circle (``diameter_m`` null) are rejected, naming the run.
    """
    profile = robot if isinstance(robot, RobotProfile) else load_robot(robot)
    if not circles:
        raise InvalidInput("circles", "no circle runs given")
    rolls: list[float] = []
    radii: list[float] = []
    plants: set[str] = set()
    for i, run in enumerate(circles):
        summ = run.get("summary", run) if isinstance(run, Mapping) else None
        if not isinstance(summ, Mapping):
            raise InvalidInput(f"circles[{i}]", "must be a circle result (JSON object with 'summary')")
        roll = summ.get("roll_desired_deg")
        diameter = summ.get("diameter_m")
        if isinstance(roll, bool) or not isinstance(roll, int | float) or not math.isfinite(roll) or roll == 0:
            raise InvalidInput(f"circles[{i}].summary.roll_desired_deg", f"must be a non-zero number, got {roll!r}")
        if isinstance(diameter, bool) or not isinstance(diameter, int | float) or not diameter > 0:
            raise InvalidInput(
                f"circles[{i}].summary.diameter_m",
                f"must be a positive number (the run turned too little to fit a circle?), got {diameter!r}",
            )
        rolls.append(math.radians(abs(float(roll))))
        radii.append(0.5 * float(diameter))
        plants.add(str(summ.get("plant", "unknown")))
    out = _fit_roll_table(rolls, radii, profile, "circles")
    out["source"] = f"circle runs on the {'/'.join(sorted(plants))} plant"
    return out


def circle_report(
    roll_rad: float,
    robot: str | RobotProfile = "daedalus",
    plant: str = "mujoco",
    duration_s: float = 30.0,
    driver: str = "vpip",
    omega_rad_s: float = 1.0,
    theta_vpip_rad: float | None = None,
    heading_rad: float = 0.0,
    contact: str | None = None,
    gains: str | None = None,
) -> dict[str, Any]:
    """Hold a roll and fit the circle rolled (``sphereplan vpip circle``; the full time series).

    ``heading_rad`` is the start heading (repeat runs: docs/vpip.md, "Held-roll circles"); ``contact`` and
    ``gains`` name the profile's contact setting and gain set (None: the profile's own)."""
    profile = robot if isinstance(robot, RobotProfile) else load_robot(robot)
    roll = _finite("roll", roll_rad)
    duration = _finite("duration", duration_s)
    omega = _finite("omega", omega_rad_s)
    theta = None if theta_vpip_rad is None else _finite("theta_vpip", theta_vpip_rad)
    heading = _finite("heading", heading_rad)
    return run_circle(
        profile, roll, duration, plant, driver, omega, theta, heading_rad=heading, contact=contact, gains=gains
    )


def calibrate_by_simulation(
    rolls_rad: list[float],
    robot: str | RobotProfile = "daedalus",
    plant: str = "mujoco",
    duration_s: float = 30.0,
    driver: str = "vpip",
    contact: str | None = None,
    gains: str | None = None,
) -> dict[str, Any]:
    """Run one circle per roll on ``plant`` and fit the roll model from them (``calibrate --rolls``).

    ``contact`` and ``gains`` pick the profile's contact setting and gain set for the runs; the result
    names them (``contact``, ``gains``) beside the table, since the table is only true for that ground."""
    profile = robot if isinstance(robot, RobotProfile) else load_robot(robot)
    if not rolls_rad:
        raise InvalidInput("rolls", "give at least one roll")
    run_profile = with_settings(profile, contact, gains)
    runs = [circle_report(r, run_profile, plant, duration_s, driver)["summary"] for r in rolls_rad]
    return {**calibrate_from_circles(runs, profile), **setting_names(run_profile), "circles": runs}


def _toml_value(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int | float):
        return repr(value)
    if isinstance(value, str):
        return '"' + value.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(value, list | tuple):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    raise InvalidInput("profile", f"cannot write {value!r} to TOML")


def profile_toml(profile: RobotProfile, roll_model: Mapping[str, Any]) -> str:
    """The profile as TOML (``profile_from_dict`` fields) with ``roll_model`` replaced."""
    top = {
        "name": profile.name,
        "description": profile.description,
        "radius_m": profile.radius_m,
        "max_roll_deg": round(math.degrees(profile.max_roll_rad), 9),
        "max_roll_rate_deg_s": round(math.degrees(profile.max_roll_rate_rad_s), 9),
        "roll_time_constant_s": profile.roll_time_constant_s,
        "max_speed_m_s": profile.max_speed_m_s,
        "max_accel_m_s2": profile.max_accel_m_s2,
        "footprint_length_m": profile.footprint_length_m,
        "footprint_width_m": profile.footprint_width_m,
    }
    lines = [f"{k} = {_toml_value(v)}" for k, v in top.items()]
    lines += _toml_table("roll_model", roll_model)
    for name, table in profile.extra.items():
        lines += _toml_table(name, table)
    return "\n".join(lines) + "\n"


def _toml_table(name: str, table: Mapping[str, Any]) -> list[str]:
    """``[name]`` with its values, then its sub-tables as ``[name.sub]`` (e.g. ``[vpip.contact_settings.paper]``)."""
    lines = ["", f"[{name}]"] + [f"{k} = {_toml_value(v)}" for k, v in table.items() if not isinstance(v, Mapping)]
    for key, value in table.items():
        if isinstance(value, Mapping):
            lines += _toml_table(f"{name}.{key}", value)
    return lines


def schedule_report(
    plan: Mapping[str, Any],
    robot: str | RobotProfile | None = None,
    driver: str = "vpip",
    plant: str = "surrogate",
    contact: str | None = None,
    gains: str | None = None,
    termination: Termination | None = None,
) -> dict[str, Any]:
    """Run the cascade along a planner result (``sphereplan vpip schedule``; the full time series).

    ``robot`` defaults to the plan's own ``robot.name``, then ``daedalus``; ``contact`` and ``gains`` pick
    the profile's contact setting and gain set (None: the profile's own); ``termination`` bounds the wall
    clock (and may cancel).
    """
    if robot is None:
        embedded = plan.get("robot") if isinstance(plan, Mapping) else None
        robot = (
            str(embedded.get("name"))
            if isinstance(embedded, Mapping) and embedded.get("name")
            else "daedalus"
        )
    profile = robot if isinstance(robot, RobotProfile) else load_robot(robot)
    return run_schedule(plan, profile, driver=driver, plant=plant, contact=contact, gains=gains,
                        termination=termination)
