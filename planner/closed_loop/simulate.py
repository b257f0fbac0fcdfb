"""The closed loop of paper 001: simulated sphere → sensors → localisation → tracker → commands, with metrics.

:func:`simulate_plan` rolls a plan (the plan-result JSON) on a map: every control period (50 Hz by
default) the encoders and IMU feed wheel odometry (eq. 2) and the fusion filter (eq. 3, GNSS fixes when
available), the tracker (the eq. 15 MPC, or pure pursuit when the solver fails in that step) computes a
command from the *estimate*, and the simulator (eq. 1 with actuator limits) moves the true sphere. The
result is the SIM.json object: ``trajectory`` (true states), ``estimate`` (fused), ``odometry``
(odometry alone), ``gnss`` fixes, ``commands`` and ``metrics``. Disturbances come from one seeded
generator, so the same inputs and seed give the same result. :func:`bench_mpc` times the MPC step.

``SimulationOptions(model="dynamic")`` replaces the kinematic simulator by paper 001's dynamic sphere
(:class:`planner.pendulum.sphere.DynamicSphere`: the eq. 16–19 plant under the LMPC speed and RSLQR roll
controllers of eq. 20–32), so the eq. 15 commands go through the motion controllers and the pendulum
before they move the robot; the profile needs a ``[dynamics]`` table.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from scipy.spatial import cKDTree

from planner.closed_loop.localization import FilterParams, FusionFilter, OdometryIncrement, WheelOdometry
from planner.closed_loop.simulator import Disturbances, SphereSimulator
from planner.closed_loop.tracker import (
    Command,
    Estimate,
    MPCParams,
    MPCTracker,
    ObstacleCircles,
    PurePursuitTracker,
    ReferencePath,
    wrap,
)
from planner.errors import InvalidInput
from planner.kinematics import SphereState
from planner.maps.clearance import least_footprint_distance
from planner.occupancy import OccupancyGrid
from planner.robot import RobotProfile, load_robot
from planner.termination import Termination

#: control steps between two looks at the wall clock (termination)
CHECK_EVERY = 20


@dataclass(frozen=True)
class SimulationOptions:
    """Closed-loop settings, checked when they are made (:class:`InvalidInput` naming the field).
    ``tracker`` is ``"mpc"`` (eq. 15) or ``"pursuit"`` (the geometric tracker alone, fast; used for long
    localisation runs). ``model`` is ``"kinematic"`` (eq. 1 with a roll lag, fast) or ``"dynamic"`` (the
    pendulum plant under LMPC + RSLQR, paper 001 §5). ``time_limit_s`` None = 2 × the path's rolling time
    at cruise speed + 20 s. ``goal_tolerance_m``: a segment is done when its end is this close along the
    end heading (as the robot believes: on its estimate). ``arrival_tolerance_m``: ``reached_goal`` needs
    the TRUE centre to end this close to the path's end as well (the estimate can be metres off without
    GNSS)."""

    control_rate_hz: float = 50.0
    substeps: int = 10
    tracker: str = "mpc"
    model: str = "kinematic"
    mpc: MPCParams = field(default_factory=MPCParams)
    filter: FilterParams = field(default_factory=FilterParams)
    time_limit_s: float | None = None
    goal_tolerance_m: float = 0.01
    arrival_tolerance_m: float = 0.25

    def __post_init__(self) -> None:
        if self.tracker not in ("mpc", "pursuit"):
            raise InvalidInput("tracker", f"must be 'mpc' or 'pursuit', got {self.tracker!r}")
        if self.model not in ("kinematic", "dynamic"):
            raise InvalidInput("model", f"must be 'kinematic' or 'dynamic', got {self.model!r}")
        if not (self.control_rate_hz > 0 and math.isfinite(self.control_rate_hz)):
            raise InvalidInput("control_rate_hz", "must be a finite number > 0")


def _robot_for(plan: dict[str, Any], robot: RobotProfile | str | None) -> RobotProfile:
    if isinstance(robot, RobotProfile):
        return robot
    if robot is not None:
        return load_robot(robot)
    name = plan.get("robot", {}).get("name") if isinstance(plan.get("robot"), dict) else None
    return load_robot(name) if name else load_robot(None)


def cross_track_distance(path_xy: np.ndarray, pts: np.ndarray) -> np.ndarray:
    """Distance (m) from each point (m, 2) to the path polyline (n, 2): nearest vertex's adjacent pieces."""
    tree = cKDTree(path_xy)
    _, idx = tree.query(pts)
    best = np.full(len(pts), np.inf)
    for off in (-1, 0):
        i0 = np.clip(idx + off, 0, len(path_xy) - 2)
        a, b = path_xy[i0], path_xy[i0 + 1]
        d = b - a
        l2 = np.maximum((d * d).sum(1), 1e-18)
        t = np.clip(((pts - a) * d).sum(1) / l2, 0.0, 1.0)
        best = np.minimum(best, np.hypot(*(a + t[:, None] * d - pts).T))
    return best


def _rows(arr: np.ndarray, keys: tuple[str, ...]) -> list[dict[str, float]]:
    return [{k: round(float(v), 6) for k, v in zip(keys, row, strict=True)} for row in arr]


@dataclass
class _Rig:
    """Everything one closed-loop run is set up with: the robot, the reference path, the seeded generators,
    the simulator and trackers, the localisation, the GNSS outages and the starting (true) state."""

    robot: RobotProfile
    dist: Disturbances
    ref: ReferencePath
    rng_slip: np.random.Generator
    rng_imu: np.random.Generator
    rng_gnss: np.random.Generator
    dt: float
    sim: SphereSimulator
    fallback: PurePursuitTracker
    mpc: MPCTracker | None
    t_limit: float
    state: SphereState
    dyn: Any
    odo: WheelOdometry
    kf: FusionFilter
    outages: list[tuple[float, float]]

    def imu(self, roll: float) -> float:
        """The IMU's roll reading (bias and noise)."""
        d = self.dist
        n = self.rng_imu.normal(0.0, d.imu_roll_noise_rad) if d.imu_roll_noise_rad > 0 else 0.0
        return roll + d.imu_roll_bias_rad + n


@dataclass
class _Run:
    """What the loop recorded: rows of (t, …) per control step, MPC solve times, fallbacks, arrival."""

    traj: list[tuple[float, ...]] = field(default_factory=list)
    est_rows: list[tuple[float, ...]] = field(default_factory=list)
    odo_rows: list[tuple[float, ...]] = field(default_factory=list)
    cmd_rows: list[tuple[float, ...]] = field(default_factory=list)
    gnss_rows: list[tuple[float, ...]] = field(default_factory=list)
    solve_ms: list[float] = field(default_factory=list)
    fallback_steps: int = 0
    reached: bool = False


def _set_up(grid: OccupancyGrid, plan_json: dict[str, Any], robot: RobotProfile | str | None, seed: int,
            dist: Disturbances, opts: SimulationOptions) -> _Rig:
    """Stage 1: the robot, the reference path, the generators (one seed), the trackers, the starting state
    (with its initial error) and the GNSS outage windows."""
    if not isinstance(plan_json, dict) or "states" not in plan_json:
        raise InvalidInput("path", "must be a plan result object with 'states'")
    rob = _robot_for(plan_json, robot)
    ref = ReferencePath(plan_json["states"])
    rng_slip, rng_imu, rng_gnss, rng_init = (
        np.random.default_rng(s) for s in np.random.SeedSequence(seed).spawn(4)
    )

    dt = 1.0 / opts.control_rate_hz
    sim = SphereSimulator(rob, opts.substeps)
    fallback = PurePursuitTracker(rob, cruise_m_s=opts.mpc.cruise_m_s)
    mpc = MPCTracker(rob, opts.mpc, ObstacleCircles(grid)) if opts.tracker == "mpc" else None
    cruise = fallback.cruise
    total_len = sum(seg.length_m for seg in ref.segments)
    t_limit = opts.time_limit_s if opts.time_limit_s is not None else 2 * total_len / cruise + 20.0

    x0, y0, yaw0, roll0 = ref.states[0, :4]
    e_xy = rng_init.normal(0.0, dist.init_xy_m, 2) if dist.init_xy_m > 0 else np.zeros(2)
    e_yaw = float(rng_init.normal(0.0, dist.init_yaw_rad)) if dist.init_yaw_rad > 0 else 0.0
    state = SphereState(x0 + e_xy[0], y0 + e_xy[1], yaw0 + e_yaw, roll0, 0.0)
    dyn = None
    if opts.model == "dynamic":
        from planner.pendulum.sphere import DynamicSphere

        dyn = DynamicSphere(rob, dt)
        dyn.reset(state.x, state.y, state.yaw, state.roll, 0.0)
    odo = WheelOdometry(rob, (x0, y0, yaw0))
    kf = FusionFilter(
        rob,
        (x0, y0, yaw0),
        FilterParams(**{**opts.filter.__dict__, "gnss_sigma_m": max(dist.gnss_noise_m, 0.005)}),
    )
    # GNSS outage windows drawn up front (Poisson starts, uniform durations)
    outages: list[tuple[float, float]] = []
    if dist.gnss_outage_rate_hz > 0:
        t_o = float(rng_gnss.exponential(1.0 / dist.gnss_outage_rate_hz))
        while t_o < t_limit:
            length = float(rng_gnss.uniform(*dist.gnss_outage_s))
            outages.append((t_o, t_o + length))
            t_o += length + float(rng_gnss.exponential(1.0 / dist.gnss_outage_rate_hz))
    return _Rig(rob, dist, ref, rng_slip, rng_imu, rng_gnss, dt, sim, fallback, mpc, t_limit, state, dyn, odo,
                kf, outages)


def _roll(rig: _Rig, opts: SimulationOptions, termination: Termination | None = None) -> _Run:
    """Stage 2: the control loop, one period per pass, until the last segment is done or time runs out."""
    dist, ref, dt, mpc, fallback, dyn = rig.dist, rig.ref, rig.dt, rig.mpc, rig.fallback, rig.dyn
    odo, kf, state = rig.odo, rig.kf, rig.state
    run = _Run()
    gnss_period = 1.0 / dist.gnss_rate_hz
    next_gnss = 0.0
    seg_i = 0
    s_proj = 0.0
    imu_prev = rig.imu(state.roll)
    wheel_dist = 0.0
    k = 0
    clock = termination.start() if termination is not None else None
    while True:
        if clock is not None and k % CHECK_EVERY == 0:
            clock.check("the simulation")
        t = k * dt
        # 1. sensors → localisation (eq. 2, eq. 3)
        imu_now = rig.imu(state.roll) if k > 0 else imu_prev
        if k > 0:
            enc = wheel_dist * (
                1.0 + (rig.rng_slip.normal(0.0, dist.encoder_noise) if dist.encoder_noise > 0 else 0.0)
            )
            inc = OdometryIncrement(enc, imu_prev, imu_now)
            odo.update(inc)
            kf.predict(inc)
        imu_prev = imu_now
        if t + 1e-9 >= next_gnss:
            next_gnss += gnss_period
            out = any(a <= t < b for a, b in rig.outages)
            if dist.gnss_available and not out:
                n_xy = rig.rng_gnss.normal(0.0, dist.gnss_noise_m, 2) if dist.gnss_noise_m > 0 else np.zeros(2)
                z = (state.x + n_xy[0], state.y + n_xy[1])
                kf.correct(z)
                run.gnss_rows.append((t, z[0], z[1]))
        est = Estimate(float(kf.pose[0]), float(kf.pose[1]), float(kf.pose[2]), imu_now, state.v)
        run.traj.append((t, state.x, state.y, state.yaw, state.roll, state.v))
        run.est_rows.append((t, *kf.pose))
        run.odo_rows.append((t, *odo.pose))
        if t >= rig.t_limit:
            break
        # 2. tracker on the estimate
        seg = ref.segments[seg_i]
        s_proj = seg.project(est.x, est.y, s_proj)
        to_go = seg.length_m - s_proj
        if to_go <= opts.goal_tolerance_m or (
            to_go < 0.5 and seg.remaining(est.x, est.y) <= opts.goal_tolerance_m
        ):
            cmd = Command(0.0, float(seg.roll[-1]))
            if abs(state.v) < 1e-3:
                if seg_i + 1 == len(ref.segments):
                    run.reached = True
                    run.cmd_rows.append((t, cmd.v, cmd.roll))
                    break
                seg_i += 1
                s_proj = 0.0
                if mpc is not None:
                    mpc.reset()
        else:
            cmd = mpc.command(est, seg, s_proj) if mpc is not None else fallback.command(est, seg, s_proj)
            if mpc is not None:
                run.solve_ms.append(cmd.solve_ms)
                if not cmd.ok:
                    run.fallback_steps += 1
                    cmd = fallback.command(est, seg, s_proj)
        run.cmd_rows.append((t, cmd.v, cmd.roll))
        # 3. the true sphere moves (eq. 1), with slip
        g = 1.0 - dist.slip_scale + (rig.rng_slip.normal(0.0, dist.slip_noise) if dist.slip_noise > 0 else 0.0)
        if dyn is not None:
            dstep = dyn.step(state, cmd.v, cmd.roll, dt, ground_factor=g)
            state = dstep.state
            wheel_dist = dstep.wheel_distance_m
        else:
            step = rig.sim.step(state, cmd.v, cmd.roll, dt, ground_factor=g)
            state, wheel_dist = step.state, step.wheel_distance_m
        k += 1
    return run


def _metrics(grid: OccupancyGrid, rig: _Rig, run: _Run, opts: SimulationOptions) -> dict[str, Any]:
    """Stage 3: how well the run went — tracking, arrival (decided by the truth), clearance, localisation."""
    tr, es, od = np.array(run.traj), np.array(run.est_rows), np.array(run.odo_rows)
    dyn, end = rig.dyn, rig.ref.end
    xt = cross_track_distance(rig.ref.polyline(), tr[:, 1:3])
    est_err = np.hypot(*(es[:, 1:3] - tr[:, 1:3]).T)
    odo_err = np.hypot(*(od[:, 1:3] - tr[:, 1:3]).T)
    clearance = least_footprint_distance(grid, rig.robot, tr[:, 1:4])
    final_error = float(math.hypot(tr[-1, 1] - end[0], tr[-1, 2] - end[1]))
    solve_ms = run.solve_ms
    return {
        "cross_track_rms_m": float(np.sqrt(np.mean(xt**2))),
        "cross_track_max_m": float(xt.max()),
        "final_position_error_m": final_error,
        "final_yaw_error_rad": abs(wrap(float(tr[-1, 3] - end[2]))),
        "min_clearance_m": clearance,
        "collided": bool(clearance <= 0.0),
        # the truth decides; the robot's own belief (stopped where its estimate said the goal is) is beside it
        "reached_goal": run.reached and final_error <= opts.arrival_tolerance_m,
        "stopped_at_estimated_goal": run.reached,
        "duration_s": float(tr[-1, 0]),
        "steps": len(run.cmd_rows),
        "fallback_steps": run.fallback_steps,
        "mpc_solve_ms_p50": float(np.percentile(solve_ms, 50)) if solve_ms else None,
        "mpc_solve_ms_p95": float(np.percentile(solve_ms, 95)) if solve_ms else None,
        "estimate_error_rms_m": float(np.sqrt(np.mean(est_err**2))),
        "estimate_error_max_m": float(est_err.max()),
        "estimate_error_final_m": float(est_err[-1]),
        "estimate_yaw_error_final_rad": abs(wrap(float(es[-1, 3] - tr[-1, 3]))),
        "odometry_error_rms_m": float(np.sqrt(np.mean(odo_err**2))),
        "odometry_error_max_m": float(odo_err.max()),
        "odometry_error_final_m": float(odo_err[-1]),
        "odometry_yaw_error_final_rad": abs(wrap(float(od[-1, 3] - tr[-1, 3]))),
        "gnss_fixes": len(run.gnss_rows),
        "pendulum_pitch_max_rad": dyn.max_pitch_rad if dyn is not None else None,
        "pendulum_roll_max_rad": dyn.max_pendulum_roll_rad if dyn is not None else None,
        "lmpc_solve_ms_p50": float(np.percentile(dyn.solve_ms, 50)) if dyn is not None and dyn.solve_ms else None,
        "lmpc_solve_ms_p95": float(np.percentile(dyn.solve_ms, 95)) if dyn is not None and dyn.solve_ms else None,
    }


def verdict(metrics: dict[str, Any], arrival_tolerance_m: float) -> tuple[str, str]:
    """``("reached", "")`` when the robot reached the path's end without touching an obstacle, else
    ``("failed", why)``: the one rule every door reports (the CLI exits 3, HTTP answers 422, Zenoh an error
    reply, the viewer says "failed" and why)."""
    why = []
    if metrics["collided"]:
        why.append(f"the robot collided (clearance {metrics['min_clearance_m']:.3f} m)")
    if not metrics["reached_goal"]:
        miss = (f"it ended {metrics['final_position_error_m']:.2f} m from the path's end "
                f"(tolerance {arrival_tolerance_m:g} m)")
        if not metrics["stopped_at_estimated_goal"]:
            miss += f" when the simulation stopped at {metrics['duration_s']:.1f} s"
        why.append(miss)
    return ("failed", "; ".join(why)) if why else ("reached", "")


#: the names of grids that came as messages (inline, nav_msgs/OccupancyGrid JSON): they say nothing of the map
UNNAMED_MAPS = frozenset({"inline", "occupancy_grid"})


def check_plan_fits(plan_json: dict[str, Any], map_name: str | None, robot_name: str | None, *,
                    allow_other_map: bool, allow_other_robot: bool, map_field: str, robot_field: str, map_flag: str,
                    robot_flag: str) -> None:
    """Refuse (:class:`InvalidInput`) to roll a plan on a map or with a robot other than the ones it was made
    for — its ``map`` and ``robot.name`` — unless allowed; ``*_field`` name the door's fields and ``*_flag``
    how to allow it there. Maps are compared by name when both are named maps (a map file or a shipped map's
    name; ``map_name`` None or an unnamed grid of :data:`UNNAMED_MAPS` is not compared). A plan without those keys
    is taken as it is."""
    planned_map = plan_json.get("map")
    named = isinstance(planned_map, str) and planned_map not in UNNAMED_MAPS
    if (named and map_name is not None and map_name not in UNNAMED_MAPS and planned_map != map_name
            and not allow_other_map):
        raise InvalidInput(map_field, f"the plan was made on map {planned_map!r}, not {map_name!r}; a plan rolled "
                                      f"on another map collides or misses its goal ({map_flag} to roll it anyway)")
    planned = plan_json.get("robot")
    planned_robot = planned.get("name") if isinstance(planned, dict) else None
    if (robot_name is not None and isinstance(planned_robot, str) and planned_robot != robot_name
            and not allow_other_robot):
        raise InvalidInput(robot_field, f"the plan was made for robot {planned_robot!r}, not {robot_name!r} "
                                        f"({robot_flag} to roll it anyway)")


def _wrapped_yaw(rows: list[tuple[float, ...]], width: int) -> np.ndarray:
    """``rows`` as an array with column 3 (yaw) wrapped to (−π, π], as every reported yaw is."""
    arr = np.array(rows).reshape(-1, width)
    arr[:, 3] = [wrap(float(a)) for a in arr[:, 3]]
    return arr


def simulate_plan(
    grid: OccupancyGrid,
    plan_json: dict[str, Any],
    robot: RobotProfile | str | None = None,
    seed: int = 0,
    noise: str | Disturbances = "default",
    options: SimulationOptions | None = None,
    termination: Termination | None = None,
) -> dict[str, Any]:
    """Roll ``plan_json`` (plan result with ``states``) on ``grid`` in closed loop; return the SIM.json dict.

    ``robot`` defaults to the plan's ``robot.name``; ``noise`` is ``"none"``, ``"default"`` or a
    :class:`Disturbances`; ``seed`` seeds every disturbance. Three stages: set up, roll, measure. ``termination``
    bounds the wall clock (and may cancel): checked every ``CHECK_EVERY`` control steps (``options.time_limit_s``
    is simulated time).
    """
    opts = options or SimulationOptions()
    dist = noise if isinstance(noise, Disturbances) else Disturbances.named(noise)
    rig = _set_up(grid, plan_json, robot, seed, dist, opts)
    run = _roll(rig, opts, termination)
    metrics = _metrics(grid, rig, run, opts)
    status, why = verdict(metrics, opts.arrival_tolerance_m)
    return {
        "status": status,
        "error_code": 0 if status == "reached" else 200,
        "error_msg": why,
        "robot": rig.robot.to_json(),
        "seed": seed,
        "noise": noise if isinstance(noise, str) else "custom",
        "tracker": opts.tracker,
        "model": opts.model,
        "control_rate_hz": opts.control_rate_hz,
        "trajectory": _rows(_wrapped_yaw(run.traj, 6), ("t", "x", "y", "yaw", "roll", "v")),
        "estimate": _rows(_wrapped_yaw(run.est_rows, 4), ("t", "x", "y", "yaw")),
        "odometry": _rows(_wrapped_yaw(run.odo_rows, 4), ("t", "x", "y", "yaw")),
        "gnss": _rows(np.array(run.gnss_rows).reshape(-1, 3), ("t", "x", "y")),
        "commands": _rows(np.array(run.cmd_rows).reshape(-1, 3), ("t", "v", "roll")),
        "metrics": metrics,
    }


__all__ = ["SimulationOptions", "check_plan_fits", "cross_track_distance", "simulate_plan", "verdict"]
