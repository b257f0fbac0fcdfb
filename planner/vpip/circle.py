"""Held-roll circle runs (paper 000 §5, Fig. 10) and open-loop pitch runs (Fig. 7) on either plant.

Paper 000 §5 holds a desired roll φ_r (roll PID, Table 1) and a rotational speed ω = 1 rad/s (pitch PI)
for 30 s and reads the circle the robot rolls: 5°, 10°, 15° gave diameters of about 2.6, 2.0 and 1.7 m.
:func:`run_circle` runs the same loop at 100 Hz — roll PID → φ_VPIP, pitch PI → θ_VPIP (or a fixed
θ_VPIP, the open-loop runs of Fig. 7), eq. 18 → rods — or the §2 simple driver, on the MuJoCo plant
(the circle comes out of the contact physics) or the surrogate (the circle comes out of the profile's roll
table, so it only reproduces the table). :func:`fit_circle` fits the rolled track.

Circle fit: algebraic least squares (Kåsa: ``x² + y² = 2ax + 2by + c``) on the centre's track after
``settle_s``; the diameter from the heading, ``2·(path length)/|Δψ|`` over the same window, is
reported beside it as a check (they agree when the track is a circle).
"""

from __future__ import annotations

import logging
import math
from typing import Any

import numpy as np

from planner.errors import InvalidInput
from planner.robot import RobotProfile
from planner.vpip.cascade import (
    MujocoSphere,
    SurrogateSphere,
    make_plant,
    plant_json,
    rod_params,
    rod_rate_stats,
    vpip_section,
)
from planner.vpip.choices import DRIVERS, PLANTS
from planner.vpip.controllers import PIDGains, PitchController, RollController, gains_from_section
from planner.vpip.mujoco_plant import Observation
from planner.vpip.rods import RodDriver, RodParams
from planner.vpip.settings import setting_names, with_settings
from planner.vpip.simple import SimpleDriver

log = logging.getLogger(__name__)

PAPER_DIAMETERS_M = {5.0: 2.6, 10.0: 2.0, 15.0: 1.7}
"""Paper 000 §5 / Fig. 10: desired roll (deg) → circle diameter (m) at ω = 1 rad/s, 30 s runs."""


def fit_circle(x: np.ndarray, y: np.ndarray) -> tuple[float, float, float, float]:
    """Kåsa least-squares circle through the points: (centre x, centre y, radius, rms residual in m)."""
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    if x.size < 3:
        raise InvalidInput("track", "needs at least three points to fit a circle")
    a = np.c_[2.0 * x, 2.0 * y, np.ones_like(x)]
    b = x * x + y * y
    (cx, cy, c), *_ = np.linalg.lstsq(a, b, rcond=None)
    r2 = c + cx * cx + cy * cy
    radius = math.sqrt(r2) if r2 > 0 else math.inf
    resid = float(np.sqrt(np.mean((np.hypot(x - cx, y - cy) - radius) ** 2))) if math.isfinite(radius) else math.inf
    return float(cx), float(cy), radius, resid


def run_circle(
    profile: RobotProfile,
    roll_rad: float,
    duration_s: float = 30.0,
    plant: str = "mujoco",
    driver: str = "vpip",
    omega_rad_s: float = 1.0,
    theta_vpip_rad: float | None = None,
    settle_s: float | None = None,
    heading_rad: float = 0.0,
    contact: str | None = None,
    gains: str | None = None,
) -> dict[str, Any]:
    """Hold a desired roll (and ω, or a fixed θ_VPIP) for ``duration_s`` and fit the circle rolled.

    Returns ``summary`` (``diameter_m`` from the fit, ``diameter_from_heading_m``, ``turned_deg``, mean
    roll and ω after ``settle_s``, rod-rate statistics) and ``series`` (t, roll, ω, φ_VPIP, θ_VPIP, x, y,
    yaw, rod lengths commanded and measured). ``diameter_m`` is null when the track turned less than
    45° (too little arc to fit a circle; a straight run). ``heading_rad`` is the start heading: on a flat
    floor it changes nothing physical, only the rounding, so repeating a MuJoCo run at several headings
    shows how much of a diameter is the run's chaotic detail (docs/vpip.md). ``contact`` and ``gains``
    pick the profile's contact setting and controller gain set (:func:`~planner.vpip.settings.with_settings`;
    None: the profile's own); the summary names both.

    Every run splits its turning into spin and lean (docs/vpip.md "The turn explained"):
    ``mean_spin_rad_s`` (Ω_z, the spin about the contact normal, > 0 turns left),
    ``mean_no_spin_yaw_rate_rad_s`` (ω_h·tan(roll), ω_h the rolling rate about the axle's horizontal
    direction: the heading rate without spin), so that yaw rate = spin + ω_h·tan(roll);
    ``mean_yaw_rate_rad_s`` (the heading rate measured), ``no_spin_diameter_m`` = 2·r_m / tan(held roll),
    the circle a non-spinning sphere rolls at the roll it actually held, and ``spin_lean_diameter_m`` =
    2·r_m / (tan(held roll) + Ω_z/ω_h), the circle the split predicts. On the MuJoCo plant the split is
    measured on the simulated body; on the surrogate the spin is what its roll table implies
    (``spin_source`` says which).
    """
    profile = with_settings(profile, contact, gains)
    _check_circle_inputs(profile, roll_rad, duration_s, plant, driver, omega_rad_s, heading_rad)
    params = rod_params(profile)
    roll_gains, pitch_gains, rate_hz = gains_from_section(vpip_section(profile))
    if theta_vpip_rad is not None and not (
        math.isfinite(theta_vpip_rad) and abs(theta_vpip_rad) <= pitch_gains.output_limit + 1e-12
    ):
        raise InvalidInput(
            "theta_vpip", f"must be within ±{math.degrees(pitch_gains.output_limit):.3g} deg, got {theta_vpip_rad!r}"
        )
    settle = min(5.0, 0.25 * duration_s) if settle_s is None else settle_s
    dt = 1.0 / rate_hz
    sphere = make_plant(plant, profile, params, 0.0, 0.0, heading_rad, roll_rad if plant == "surrogate" else 0.0)
    loop = _HeldRollLoop(sphere, params, roll_gains, pitch_gains, dt, driver)
    loop.run(roll_rad, omega_rad_s, theta_vpip_rad, duration_s, settle)
    summary = _summary(loop.rec, dt, settle, params.rod_speed_m_s)
    summary.update(
        {
            "plant": plant,
            "driver": driver,
            **setting_names(profile),
            "roll_desired_deg": math.degrees(roll_rad),
            "omega_desired_rad_s": omega_rad_s if theta_vpip_rad is None else None,
            "theta_vpip_fixed_deg": None if theta_vpip_rad is None else math.degrees(theta_vpip_rad),
            "duration_s": duration_s,
            "settle_s": settle,
            "start_heading_rad": heading_rad,
            "commanded_rod_rate": rod_rate_stats(np.asarray(loop.rec["rod_length_m"]), dt, params.rod_speed_m_s),
        }
    )
    summary.update(_plant_summary(loop, dt, settle, params))
    summary.update(_turn_split(loop.rec, settle, params.r_m, summary["mean_roll_deg"], summary["mean_yaw_rate_rad_s"]))
    if loop.roll_sat:
        summary.update(_roll_pid_summary(loop, roll_gains.integral_limit, int(settle / dt)))
    paper = PAPER_DIAMETERS_M.get(round(abs(math.degrees(roll_rad)), 6))
    summary["paper_diameter_m"] = paper
    if paper is not None and summary["diameter_m"] is not None:
        summary["relative_to_paper"] = summary["diameter_m"] / paper - 1.0
    log.info("circle %s/%s roll %.1f deg: %s", plant, driver, math.degrees(roll_rad), summary["diameter_m"])
    return {
        "robot": profile.name,
        "rate_hz": rate_hz,
        "plant": plant_json(sphere),
        "params": params.to_json(),
        "summary": summary,
        "series": loop.rec,
    }


def _check_circle_inputs(
    profile: RobotProfile,
    roll_rad: float,
    duration_s: float,
    plant: str,
    driver: str,
    omega_rad_s: float,
    heading_rad: float,
) -> None:
    """Refuse a circle request naming the bad field (:class:`~planner.errors.InvalidInput`)."""
    if driver not in DRIVERS:
        raise InvalidInput("driver", f"must be one of {', '.join(DRIVERS)}, got {driver!r}")
    if plant not in PLANTS:
        raise InvalidInput("plant", f"must be one of {', '.join(PLANTS)}, got {plant!r}")
    for name, value in (("roll", roll_rad), ("duration", duration_s), ("omega", omega_rad_s)):
        if not math.isfinite(value):
            raise InvalidInput(name, f"must be finite, got {value!r}")
    if not math.isfinite(heading_rad):
        raise InvalidInput("heading", f"must be finite, got {heading_rad!r}")
    if abs(roll_rad) > profile.max_roll_rad + 1e-12:
        raise InvalidInput(
            "roll", f"|roll| must be at most the profile's max roll {math.degrees(profile.max_roll_rad):.3g} deg"
        )
    if not 0 < duration_s <= 600:
        raise InvalidInput("duration", f"must be in (0, 600] s, got {duration_s}")
    if not 0 < omega_rad_s <= 5:
        raise InvalidInput("omega", f"must be in (0, 5] rad/s, got {omega_rad_s}")


class _HeldRollLoop:
    """The 100 Hz loop of a circle run: controllers → rods → plant, recording every tick in :attr:`rec`."""

    def __init__(
        self,
        sphere: SurrogateSphere | MujocoSphere,
        params: RodParams,
        roll_gains: PIDGains,
        pitch_gains: PIDGains,
        dt: float,
        driver: str,
    ) -> None:
        self.sphere = sphere
        self.params = params
        self.dt = dt
        self.driver = driver
        self.roll_ctl = RollController(roll_gains, dt)
        self.pitch_ctl = PitchController(pitch_gains, dt)
        self.vpip = RodDriver(params, dt)
        self.simple = SimpleDriver(params, dt)
        keys = ["t", "roll_rad", "omega_rad_s", "phi_vpip_rad", "theta_vpip_rad", "x", "y", "yaw", "rod_length_m"]
        if isinstance(sphere, MujocoSphere):
            keys += ["rod_measured_m", "rods_on_ground", "spin_rad_s", "no_spin_yaw_rate_rad_s"]
        self.rec: dict[str, list[Any]] = {k: [] for k in keys}
        self.feet = _FootStats(params.rods_per_side)
        self.roll_sat: list[bool] = []
        self.roll_int: list[float] = []
        self.roll_d: list[float] = []

    def run(
        self, roll_rad: float, omega_rad_s: float, theta_vpip_rad: float | None, duration_s: float, settle: float
    ) -> None:
        dt, sphere = self.dt, self.sphere
        steps = round(duration_s / dt)
        for k in range(steps + 1):
            obs = sphere.observe()
            phi_v, theta_v, lengths = self._command(obs, roll_rad, omega_rad_s, theta_vpip_rad)
            self._record(k * dt, obs, phi_v, theta_v, lengths)
            if isinstance(sphere, MujocoSphere) and k * dt >= settle:
                self.feet.tick(sphere.sim, obs, roll_rad)
            if k < steps:
                sphere.step(phi_v, theta_v, lengths, dt)

    def _command(
        self, obs: Observation, roll_rad: float, omega_rad_s: float, theta_vpip_rad: float | None
    ) -> tuple[float, float, np.ndarray]:
        """This tick's plane angles (NaN for the simple driver) and rod lengths."""
        if self.driver == "vpip":
            roll_ctl = self.roll_ctl
            phi_v = roll_ctl.command(obs.roll_rad, roll_rad)
            theta_v = (
                self.pitch_ctl.command(obs.omega_rad_s, omega_rad_s) if theta_vpip_rad is None else theta_vpip_rad
            )
            self.vpip.step(phi_v, theta_v, obs.roll_rad, obs.phase_rad)
            self.roll_sat.append(roll_ctl.saturated)
            self.roll_int.append(roll_ctl.integral)
            self.roll_d.append(roll_ctl.gains.kd * roll_ctl.derivative)
            return phi_v, theta_v, self.vpip.lengths_m
        self.simple.step(obs.roll_rad, roll_rad, obs.phase_rad)
        return math.nan, math.nan, self.simple.lengths_m

    def _record(self, t: float, obs: Observation, phi_v: float, theta_v: float, lengths: np.ndarray) -> None:
        rec = self.rec
        for key, value in (
            ("t", t),
            ("roll_rad", obs.roll_rad),
            ("omega_rad_s", obs.omega_rad_s),
            ("phi_vpip_rad", phi_v),
            ("theta_vpip_rad", theta_v),
            ("x", obs.x),
            ("y", obs.y),
            ("yaw", obs.yaw),
        ):
            rec[key].append(float(value) if math.isfinite(value) else None)
        rec["rod_length_m"].append([float(v) for v in lengths])
        if isinstance(self.sphere, MujocoSphere):
            sim = self.sphere.sim
            rec["rod_measured_m"].append([float(v) for v in sim.rod_lengths_m()])
            rec["rods_on_ground"].append(int(sim.rods_on_ground().sum()))
            w, tilt = sim.turn_rates()
            rec["spin_rad_s"].append(w)
            rec["no_spin_yaw_rate_rad_s"].append(tilt)


def _plant_summary(loop: _HeldRollLoop, dt: float, settle: float, params: RodParams) -> dict[str, Any]:
    """What the plant says about itself: measured rod rates, feet and the source of the diameter."""
    sphere, rec = loop.sphere, loop.rec
    if not isinstance(sphere, MujocoSphere):
        return {"diameter_source": "surrogate: the profile's roll model (table), not physics"}
    measured = np.asarray(rec["rod_measured_m"])
    return {
        "measured_rod_rate": rod_rate_stats(measured, dt, params.rod_speed_m_s),
        "peak_rod_speed_m_s": sphere.sim.peak_rod_speed_m_s,
        "max_rod_length_m": float(measured.max()),
        "mean_rods_on_ground": float(np.mean(rec["rods_on_ground"])),
        "diameter_source": "MuJoCo rigid-body contact physics",
        "rod_feet": loop.feet.summary(),
    }


def _turn_split(
    rec: dict[str, list[Any]], settle: float, r_m: float, mean_roll_deg: float, mean_yaw_rate: float
) -> dict[str, Any]:
    """Heading rate = spin Ω_z + ω_h·tan(roll), averaged after ``settle`` (see :func:`run_circle`)."""
    t = np.asarray(rec["t"])
    late = t >= settle
    if "spin_rad_s" in rec:
        spin = float(np.mean(np.asarray(rec["spin_rad_s"])[late]))
        tilt = float(np.mean(np.asarray(rec["no_spin_yaw_rate_rad_s"])[late]))
        source = "measured: the simulated body's angular velocity (MujocoPlant.turn_rates)"
    else:
        omega = np.asarray(rec["omega_rad_s"], dtype=float)[late]
        tilt = float(np.mean(omega * np.tan(np.asarray(rec["roll_rad"], dtype=float)[late])))
        spin = mean_yaw_rate - tilt
        source = "implied: the surrogate turns by the profile's roll table; spin = yaw rate - omega tan(roll)"
    held = math.radians(abs(mean_roll_deg))
    omega_h = float(np.mean(np.asarray(rec["omega_rad_s"], dtype=float)[late]))
    lean = math.tan(math.radians(mean_roll_deg))
    denominator = lean + spin / omega_h if abs(omega_h) > 1e-6 else 0.0
    return {
        "mean_spin_rad_s": spin,
        "mean_no_spin_yaw_rate_rad_s": tilt,
        "held_roll_deg": mean_roll_deg,
        "no_spin_diameter_m": 2.0 * r_m / math.tan(held) if held > 1e-6 else None,
        "spin_lean_diameter_m": abs(2.0 * r_m / denominator) if abs(denominator) > 1e-9 else None,
        "spin_source": source,
    }


def _roll_pid_summary(loop: _HeldRollLoop, integral_limit: float, settle_ticks: int) -> dict[str, Any]:
    """How the roll PID spent the run after settling: at its output limit, integral at its limit, parts."""
    n_late = len(loop.roll_sat) - settle_ticks
    if n_late <= 0:
        return {}
    late_int = np.abs(loop.roll_int[-n_late:])
    return {
        "roll_pid": {
            "output_saturated_fraction": float(np.mean(loop.roll_sat[-n_late:])),
            "integral_at_limit_fraction": float(np.mean(late_int >= integral_limit * (1 - 1e-9))),
            "mean_integral_deg": math.degrees(float(np.mean(loop.roll_int[-n_late:]))),
            "rms_derivative_part_deg": math.degrees(float(np.sqrt(np.mean(np.square(loop.roll_d[-n_late:]))))),
        }
    }


class _FootStats:
    """Where and how the rod feet touch the floor during a circle run (docs/vpip.md, hypothesis a).

    Per control tick after settling: every foot contact's offset from the shell's contact (the point under
    the centre) in the heading frame (``lateral_m`` > 0 right, ``forward_m`` > 0 ahead), the force on the
    robot (normal, forward, ``inward_n``: lateral, towards the centre-line), whether the foot slides
    (> 1 cm/s), and the yaw moment of the foot forces about the shell's contact (N m, > 0 turns left),
    split into the feet on the low side of the lean (the side of the desired roll) and the high side.
    """

    def __init__(self, rods_per_side: int) -> None:
        self.n = rods_per_side
        self.ticks = 0
        self.ticks_with_contact = 0
        self.rows: dict[str, list[tuple[float, float, float, float, float, float, float]]] = {"low": [], "high": []}

    def tick(self, sim: Any, obs: Any, desired_roll_rad: float) -> None:
        self.ticks += 1
        contacts = sim.foot_contacts()
        if contacts:
            self.ticks_with_contact += 1
        fwd = np.array([math.cos(obs.yaw), math.sin(obs.yaw)])
        right = np.array([math.sin(obs.yaw), -math.cos(obs.yaw)])
        centre = np.array([obs.x, obs.y])
        for rod, pos, force, slip in contacts:
            rel = pos[:2] - centre
            lat, ahead = float(rel @ right), float(rel @ fwd)
            f_fwd, f_right = float(force[:2] @ fwd), float(force[:2] @ right)
            left = rod < self.n
            low = left if desired_roll_rad >= 0 else not left
            inward = -f_right if lat > 0 else f_right
            moment = lat * f_fwd - ahead * f_right
            self.rows["low" if low else "high"].append(
                (lat, ahead, float(force[2]), f_fwd, inward, 1.0 if slip > 0.01 else 0.0, moment)
            )

    def summary(self) -> dict[str, Any]:
        out: dict[str, Any] = {
            "ticks_with_a_foot_down_fraction": self.ticks_with_contact / self.ticks if self.ticks else None
        }
        for side, rows in self.rows.items():
            if not rows:
                out[side] = None
                continue
            a = np.asarray(rows)
            w = np.maximum(a[:, 2], 0.0)
            out[side] = {
                "contact_ticks": len(rows),
                "mean_lateral_m": float(a[:, 0].mean()),
                "mean_forward_m": float(a[:, 1].mean()),
                "mean_normal_n": float(a[:, 2].mean()),
                "mean_forward_force_n": float(a[:, 3].mean()),
                "mean_inward_force_n": float(a[:, 4].mean()),
                "sliding_force_weighted_fraction": float(np.sum(w * a[:, 5]) / np.sum(w)) if w.sum() > 0 else None,
                "yaw_moment_time_mean_n_m": float(a[:, 6].sum() / self.ticks),
            }
        return out


def _summary(rec: dict[str, list[Any]], dt: float, settle_s: float, rod_speed: float) -> dict[str, Any]:
    t = np.asarray(rec["t"])
    late = t >= settle_s
    if late.sum() < 3:
        raise InvalidInput("duration", f"must be longer than the settling time {settle_s} s")
    x = np.asarray(rec["x"])[late]
    y = np.asarray(rec["y"])[late]
    yaw = np.unwrap(np.asarray(rec["yaw"]))[late]
    roll = np.asarray(rec["roll_rad"])[late]
    omega = np.asarray(rec["omega_rad_s"])[late]
    path = float(np.sum(np.hypot(np.diff(x), np.diff(y))))
    turned = float(yaw[-1] - yaw[0])
    cx, cy, radius, resid = fit_circle(x, y)
    enough = abs(turned) >= math.radians(45.0) and math.isfinite(radius)
    return {
        "diameter_m": 2.0 * radius if enough else None,
        "circle_centre_m": [cx, cy] if enough else None,
        "fit_rms_m": resid if enough else None,
        "diameter_from_heading_m": 2.0 * path / abs(turned) if abs(turned) > 1e-9 else None,
        "turned_deg": math.degrees(turned),
        "path_length_m": path,
        "mean_speed_m_s": path / float(t[late][-1] - t[late][0]),
        "mean_yaw_rate_rad_s": turned / float(t[late][-1] - t[late][0]),
        "mean_roll_deg": math.degrees(float(np.mean(roll))),
        "std_roll_deg": math.degrees(float(np.std(roll))),
        "mean_omega_rad_s": float(np.mean(omega)),
        "std_omega_rad_s": float(np.std(omega)),
    }
