"""The curvature cascade: a planned path → desired roll and speed → VPIP angles → 16 rod lengths.

Paper 000 §5 ends with the cascade this module runs ("control the desired φ_r of the robot over a
desired curve radius"): at every control tick (100 Hz)

1. the path's curvature (plus a small path-tracking correction) gives the desired turning radius and,
   through the profile's :class:`~planner.robot.RollModel`, the desired roll (rate-limited to the
   profile's roll rate);
2. the plan's time parametrisation gives the desired speed, ω = v / r_m;
3. the roll PID gives φ_VPIP, the pitch PI gives θ_VPIP (:mod:`planner.vpip.controllers`);
4. the rod driver turns them into the 16 rod lengths (eq. 18, :mod:`planner.vpip.rods`), each
   rate-limited to the rod speed — or the §2 baseline (:mod:`planner.vpip.simple`) does.

**The plant is a surrogate, not the rod physics.** The robot's rotational speed follows θ_VPIP
through a first-order lag with a rate limit: ``ω → G_ω · θ_VPIP`` (time constant
``plant_omega_tau_s`` = 0.5 s, ω̇ ≤ ``max_accel / r_m``). The roll follows φ_VPIP through a damped
*second-order* lag with a rate limit: ``φ̈ = ω_n²(−G_φ · φ_VPIP − φ) − 2ζω_n φ̇``, ``|φ̇| ≤ max_roll_rate``
(ω_n = 2 rad/s, ζ = 0.7). A first-order lag is not used for roll because Table 1's roll PID has a
large derivative (k_d/k_p ≈ 1.2 s, tuned on an inertial plant): against any first-order lag fast
enough to matter the derivative feed-through makes the 100 Hz loop chatter between ±20°, and a lag slow
enough to be stable (G_φ/τ ≲ 0.4 1/s) cannot hold 15° roll within the 5° integral limit.
G_φ = 3 (roll per rad of φ_VPIP; G_φ ≥ 3 lets the 5° integral part hold the 15° table roll with no
steady error) and G_ω = 3 rad/s per rad (ω = 1 rad/s of paper §5 at θ_VPIP ≈ 19°, inside the 10°–30°
band of paper Fig. 7) are assumptions; ``[vpip]`` keys ``plant_roll_gain``, ``plant_roll_natural_rad_s``,
``plant_roll_damping``, ``plant_omega_gain``, ``plant_omega_tau_s`` override them. The simple driver
has no plane, so its rod targets (before the rod-speed limit, as the VPIP driver's plane is) are
mapped to the plane angles that best reproduce them (:func:`rods.equivalent_plane`) and those drive
the same plant. The sphere then moves by paper 001 eq. 1 with the profile's roll model:
``ẋ = v cos ψ − r φ̇ sin ψ``, ``ẏ = v sin ψ + r φ̇ cos ψ``, ``ψ̇ = v·κ(φ)``.

``plant="mujoco"`` replaces the surrogate and the eq. 1 kinematics with the rod physics
(:mod:`planner.vpip.mujoco_plant`): the same controllers read roll, ω, pitch phase and pose from the
simulated body and the rods' commanded lengths drive its 16 slide joints; the sphere turns however the
contacts make it turn (the roll model is then only used to choose the desired roll).

Reverse motion (negative ``v`` in the plan) is not supported.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from planner.errors import InvalidInput, RobotProfileError
from planner.kinematics import wrap
from planner.result import state_column
from planner.robot import RobotProfile
from planner.termination import Termination
from planner.vpip.choices import DRIVERS, PLANTS
from planner.vpip.controllers import PitchController, RollController, gains_from_section
from planner.vpip.mujoco_plant import MujocoPlant, Observation
from planner.vpip.rods import RodDriver, RodParams, equivalent_plane
from planner.vpip.settings import setting_names, with_settings
from planner.vpip.simple import SimpleDriver

#: control ticks between two looks at the wall clock (termination)
CHECK_EVERY = 20

SURROGATE_NOTE = (
    "surrogate plant, not the rod/contact physics: rotational speed follows theta_vpip through a "
    "first-order lag, roll follows phi_vpip through a damped second-order lag, both rate-limited"
)
MUJOCO_NOTE = (
    "MuJoCo rigid-body model: shell, baseplate, battery pendulum and 16 rods on slide joints with position "
    "servos; the commanded rod lengths drive it and roll, omega, pitch phase and pose are read from the body"
)


def vpip_section(profile: RobotProfile) -> Mapping[str, Any]:
    """The profile's ``[vpip]`` table; a profile without one cannot drive rods."""
    section = profile.extra.get("vpip")
    if not isinstance(section, Mapping):
        raise InvalidInput(
            "robot", f"profile {profile.name!r} has no [vpip] section (rod-driven robots only)"
        )
    return section


def rod_params(profile: RobotProfile) -> RodParams:
    return RodParams.from_section(vpip_section(profile))


@dataclass(frozen=True)
class PlantParams:
    """Surrogate plant (see module doc). Gains: roll (rad per rad of φ_VPIP), ω (rad/s per rad of θ_VPIP)."""

    roll_gain: float
    roll_natural_rad_s: float
    roll_damping: float
    roll_rate_rad_s: float
    omega_gain: float
    omega_tau_s: float
    omega_accel_rad_s2: float

    @classmethod
    def from_profile(cls, profile: RobotProfile, params: RodParams) -> PlantParams:
        section = vpip_section(profile)

        def num(key: str, default: float) -> float:
            value = section.get(key, default)
            if isinstance(value, bool) or not isinstance(value, int | float) or not 0 < float(value) < 1e6:
                raise RobotProfileError(f"vpip.{key}", f"must be a number > 0, got {value!r}")
            return float(value)

        return cls(
            roll_gain=num("plant_roll_gain", 3.0),
            roll_natural_rad_s=num("plant_roll_natural_rad_s", 2.0),
            roll_damping=num("plant_roll_damping", 0.7),
            roll_rate_rad_s=profile.max_roll_rate_rad_s,
            omega_gain=num("plant_omega_gain", 3.0),
            omega_tau_s=num("plant_omega_tau_s", 0.5),
            omega_accel_rad_s2=profile.max_accel_m_s2 / params.r_m,
        )


def _lag(value: float, target: float, tau_s: float, rate: float, dt_s: float) -> float:
    """One step of a first-order lag toward ``target`` whose rate is limited to ``rate``."""
    change = (target - value) * (1.0 - math.exp(-dt_s / tau_s))
    return value + max(-rate * dt_s, min(rate * dt_s, change))


class SurrogatePlant:
    """Roll (rad, > 0 left) and rotational speed ω (rad/s) responding to the VPIP angles; a surrogate."""

    def __init__(self, p: PlantParams, roll_rad: float = 0.0, omega_rad_s: float = 0.0) -> None:
        self.p = p
        self.roll_rad = roll_rad
        self.roll_rate_rad_s = 0.0
        self.omega_rad_s = omega_rad_s

    def step(self, phi_vpip_rad: float, theta_vpip_rad: float, dt_s: float) -> None:
        p = self.p
        wn = p.roll_natural_rad_s
        acc = (
            wn * wn * (-p.roll_gain * phi_vpip_rad - self.roll_rad)
            - 2.0 * p.roll_damping * wn * self.roll_rate_rad_s
        )
        rate = self.roll_rate_rad_s + acc * dt_s
        self.roll_rate_rad_s = max(-p.roll_rate_rad_s, min(p.roll_rate_rad_s, rate))
        self.roll_rad += self.roll_rate_rad_s * dt_s
        self.omega_rad_s = _lag(
            self.omega_rad_s, p.omega_gain * theta_vpip_rad, p.omega_tau_s, p.omega_accel_rad_s2, dt_s
        )


class SurrogateSphere:
    """:class:`SurrogatePlant` plus the sphere's motion by paper 001 eq. 1 with the profile's roll model.

    Same interface as :class:`~planner.vpip.mujoco_plant.MujocoPlant` (``observe``, ``step``) so the
    cascade can drive either; it moves on the plane angles and ignores the rod lengths.
    """

    def __init__(
        self, p: PlantParams, profile: RobotProfile, x: float, y: float, yaw: float, roll_rad: float
    ) -> None:
        self.plant = SurrogatePlant(p, roll_rad=roll_rad, omega_rad_s=0.0)
        self.profile = profile
        self.x, self.y, self.yaw, self.phase = x, y, yaw, 0.0

    def observe(self) -> Observation:
        return Observation(self.plant.roll_rad, self.plant.omega_rad_s, self.phase, self.x, self.y, self.yaw)

    def step(self, phi_vpip_rad: float, theta_vpip_rad: float, rod_lengths_m: np.ndarray, dt_s: float) -> None:
        roll, omega = self.plant.roll_rad, self.plant.omega_rad_s
        self.plant.step(phi_vpip_rad, theta_vpip_rad, dt_s)
        roll_rate = (self.plant.roll_rad - roll) / dt_s
        r = self.profile.radius_m
        v = omega * r
        yaw_new = self.yaw + v * float(self.profile.roll_model.curvature(roll)) * dt_s
        self.x += (v * math.cos(self.yaw) - r * roll_rate * math.sin(self.yaw)) * dt_s
        self.y += (v * math.sin(self.yaw) + r * roll_rate * math.cos(self.yaw)) * dt_s
        self.yaw = yaw_new
        self.phase += omega * dt_s


class MujocoSphere:
    """:class:`~planner.vpip.mujoco_plant.MujocoPlant` behind the cascade's plant interface (rods only)."""

    def __init__(self, profile: RobotProfile, params: RodParams, x: float, y: float, yaw: float) -> None:
        from planner.vpip.mujoco_model import BodyParams

        self.body = BodyParams.from_section(vpip_section(profile))
        self.sim = MujocoPlant(params, self.body, x=x, y=y, yaw=yaw)

    def observe(self) -> Observation:
        return self.sim.observe()

    def step(self, phi_vpip_rad: float, theta_vpip_rad: float, rod_lengths_m: np.ndarray, dt_s: float) -> None:
        self.sim.step(rod_lengths_m, dt_s)


def make_plant(
    plant: str, profile: RobotProfile, params: RodParams, x: float, y: float, yaw: float, roll_rad: float = 0.0
) -> SurrogateSphere | MujocoSphere:
    """The cascade's plant: ``"surrogate"`` (fast default) or ``"mujoco"`` (rod physics, starts upright)."""
    if plant not in PLANTS:
        raise InvalidInput("plant", f"must be one of {', '.join(PLANTS)}, got {plant!r}")
    if plant == "mujoco":
        return MujocoSphere(profile, params, x, y, yaw)
    return SurrogateSphere(PlantParams.from_profile(profile, params), profile, x, y, yaw, roll_rad)


def plant_json(sphere: SurrogateSphere | MujocoSphere) -> dict[str, Any]:
    """What the result says about its plant: kind, a note, and the plant's parameters."""
    if isinstance(sphere, MujocoSphere):
        return {"kind": "mujoco", "note": MUJOCO_NOTE, **sphere.body.to_json()}
    p = sphere.plant.p
    return {"kind": "surrogate", "note": SURROGATE_NOTE, **{k: getattr(p, k) for k in p.__dataclass_fields__}}


@dataclass(frozen=True)
class PathReference:
    """The planned path as arrays over arc length ``s`` (m): pose, curvature (1/m), time (s), speed (m/s)."""

    s: np.ndarray
    x: np.ndarray
    y: np.ndarray
    yaw: np.ndarray
    curvature: np.ndarray
    t: np.ndarray
    v: np.ndarray

    @classmethod
    def from_plan(cls, plan: Mapping[str, Any], profile: RobotProfile) -> PathReference:
        """Read a planner result (docs/contracts.md: ``states`` [{x, y, yaw, roll, v, t, s, curvature}])."""
        if not isinstance(plan, Mapping):
            raise InvalidInput("path", "must be a JSON object with 'states'")
        states = plan.get("states")
        if not isinstance(states, list) or len(states) < 2:
            raise InvalidInput("path.states", "must be a list of at least two states")
        x = state_column(states, "x", True)
        y = state_column(states, "y", True)
        yaw = state_column(states, "yaw", True)
        assert x is not None and y is not None and yaw is not None
        yaw = np.unwrap(yaw)
        seg = np.hypot(np.diff(x), np.diff(y))
        s = state_column(states, "s", False)
        if s is None:
            s = np.concatenate([[0.0], np.cumsum(seg)])
        if np.any(np.diff(s) < 0):
            raise InvalidInput("path.states.s", "must not decrease along the path")
        keep = np.concatenate([[True], np.diff(s) > 1e-9])
        if keep.sum() < 2:
            raise InvalidInput("path.states", "the path has zero length")
        v = state_column(states, "v", False)
        if v is not None and np.any(v < 0):
            raise InvalidInput(
                "path.states.v", "reverse motion (v < 0) is not supported by the VPIP schedule"
            )
        t = state_column(states, "t", False)
        if t is None or np.any(np.diff(t[keep]) <= 0):
            t = s / profile.max_speed_m_s
        if v is None:
            v = (
                np.gradient(s[keep], t[keep])
                if keep.sum() > 2
                else np.full(int(keep.sum()), profile.max_speed_m_s)
            )
            v_full = np.interp(s, s[keep], v)
        else:
            v_full = v
        k = state_column(states, "curvature", False)
        if k is None:
            k = np.gradient(yaw[keep], s[keep])
            k = np.interp(s, s[keep], k)
        return cls(s[keep], x[keep], y[keep], yaw[keep], k[keep], t[keep], v_full[keep])

    @property
    def length_m(self) -> float:
        return float(self.s[-1] - self.s[0])

    def pose_at(self, s: float) -> tuple[float, float, float]:
        return (
            float(np.interp(s, self.s, self.x)),
            float(np.interp(s, self.s, self.y)),
            float(np.interp(s, self.s, self.yaw)),
        )

    def curvature_at(self, s: float) -> float:
        return float(np.interp(s, self.s, self.curvature))

    def s_at_t(self, t: float) -> float:
        return float(np.interp(t, self.t, self.s))

    def v_at_t(self, t: float) -> float:
        return float(np.interp(t, self.t, self.v))


@dataclass(frozen=True)
class TrackingGains:
    """Path-tracking correction on top of the path curvature (assumptions, not from the paper).

    κ_cmd = κ_path(s + v·lookahead) + k_heading·(ψ_ref − ψ) − k_lateral·e_lat, e_lat > 0 left of the path;
    desired speed = v_plan(t) + k_progress·(s_plan(t) − s).
    """

    k_heading_per_m: float = 1.5
    k_lateral_per_m2: float = 1.0
    k_progress_per_s: float = 0.5
    lookahead_s: float = 0.5


def rod_rate_stats(lengths_m: np.ndarray, dt_s: float, limit_m_s: float) -> dict[str, float]:
    """Statistics of a (ticks × rods) length series' per-tick rates: max, 95th percentile, mean |rate|,
    and the share of rod-ticks moving at (within 1 % of) the limit."""
    if len(lengths_m) < 2:
        return {"max_m_s": 0.0, "p95_m_s": 0.0, "mean_abs_m_s": 0.0, "share_at_limit": 0.0}
    rate = np.abs(np.diff(lengths_m, axis=0)) / dt_s
    return {
        "max_m_s": float(rate.max()),
        "p95_m_s": float(np.percentile(rate, 95)),
        "mean_abs_m_s": float(rate.mean()),
        "share_at_limit": float(np.mean(rate >= 0.99 * limit_m_s)),
    }


def run_schedule(
    plan: Mapping[str, Any],
    profile: RobotProfile,
    driver: str = "vpip",
    tracking: TrackingGains | None = None,
    max_duration_s: float | None = None,
    plant: str = "surrogate",
    contact: str | None = None,
    gains: str | None = None,
    termination: Termination | None = None,
) -> dict[str, Any]:
    """Run the cascade along ``plan`` and return the time series (JSON-ready, SI units, radians).
    ``termination`` (wall clock, cancel) is checked every ``CHECK_EVERY`` ticks.

    ``series`` holds, per tick: t, desired and simulated roll, desired and simulated ω, φ_VPIP,
    θ_VPIP, the pitch phase, the tracked pose (x, y, yaw, s) and ``rod_length_m`` (ticks × 2n commanded
    lengths after the rod-speed limit); with ``plant="mujoco"`` also ``rod_measured_m`` (the slide
    joints' positions) and ``rods_on_ground`` (how many rod tips touch the floor). Stops when the end of
    the path is reached or after ``max_duration_s`` (default: 1.5 × the plan's duration + 10 s; on the
    MuJoCo plant 3 × + 20 s, room for a sphere that falls behind the plan's timing). ``contact`` and
    ``gains`` pick the profile's contact setting and gain set (:func:`~planner.vpip.settings.with_settings`).
    """
    if driver not in DRIVERS:
        raise InvalidInput("driver", f"must be one of {', '.join(DRIVERS)}, got {driver!r}")
    if plant not in PLANTS:
        raise InvalidInput("plant", f"must be one of {', '.join(PLANTS)}, got {plant!r}")
    profile = with_settings(profile, contact, gains)
    cascade = _Cascade(plan, profile, driver, tracking or TrackingGains(), plant)
    t_end = float(cascade.ref.t[-1] - cascade.ref.t[0])
    default_limit = 3.0 * t_end + 20.0 if plant == "mujoco" else 1.5 * t_end + 10.0
    cascade.run(max_duration_s if max_duration_s is not None else default_limit, termination)
    n = cascade.params.rods_per_side
    return {
        "driver": driver,
        "robot": profile.name,
        "rate_hz": cascade.rate_hz,
        "plant": plant_json(cascade.sphere),
        "params": cascade.params.to_json(),
        "rods": [{"index": i, "side": "left" if i < n else "right"} for i in range(2 * n)],
        "summary": cascade.summary(),
        "series": cascade.rec,
    }


_SCHEDULE_KEYS = (
    "t",
    "roll_desired_rad",
    "roll_rad",
    "omega_desired_rad_s",
    "omega_rad_s",
    "phi_vpip_rad",
    "theta_vpip_rad",
    "pitch_phase_rad",
    "curvature_cmd",
    "x",
    "y",
    "yaw",
    "s",
    "lateral_error_m",
)
"""The scalar series of a schedule, in the order they are recorded."""


class _Cascade:
    """One run of the module's cascade along a plan: set-up here, :meth:`run` the loop, :meth:`summary`."""

    def __init__(
        self, plan: Mapping[str, Any], profile: RobotProfile, driver: str, tracking: TrackingGains, plant: str
    ) -> None:
        self.profile = profile
        self.driver = driver
        self.tracking = tracking
        self.plant = plant
        self.params = params = rod_params(profile)
        self.roll_gains, self.pitch_gains, self.rate_hz = gains_from_section(vpip_section(profile))
        self.ref = ref = PathReference.from_plan(plan, profile)
        self.dt = dt = 1.0 / self.rate_hz
        self.t_end = float(ref.t[-1] - ref.t[0])
        model = profile.roll_model
        self.max_k = profile.max_curvature
        self.max_roll = profile.max_roll_rad
        self.max_omega = profile.max_speed_m_s / params.r_m
        roll0 = float(model.roll_for_curvature(ref.curvature[0]))
        roll0 = max(-self.max_roll, min(self.max_roll, roll0))
        self.roll_ctl = RollController(self.roll_gains, dt)
        self.pitch_ctl = PitchController(self.pitch_gains, dt)
        self.vpip = RodDriver(params, dt)
        self.simple = SimpleDriver(params, dt)
        self.sphere = make_plant(plant, profile, params, float(ref.x[0]), float(ref.y[0]), float(ref.yaw[0]), roll0)
        self.obs = self.sphere.observe()
        self.roll_des = self.obs.roll_rad if plant == "mujoco" else roll0
        self.s_sim = float(ref.s[0])
        self.s_goal = float(ref.s[-1])
        keys = [*_SCHEDULE_KEYS, "rod_length_m"]
        if plant == "mujoco":
            keys += ["rod_measured_m", "rods_on_ground"]
        self.rec: dict[str, list[Any]] = {k: [] for k in keys}
        self.max_lat = 0.0
        self.reached = False

    def run(self, limit_s: float, termination: Termination | None = None) -> None:
        """Tick at the control rate until the end of the path is reached or ``limit_s`` (simulated) has passed;
        ``termination`` bounds the wall clock."""
        steps = math.ceil(limit_s / self.dt)
        clock = termination.start() if termination is not None else None
        for k in range(steps + 1):
            if clock is not None and k % CHECK_EVERY == 0:
                clock.check("the VPIP schedule")
            t = k * self.dt
            obs = self.obs
            yawr, e_lat, k_cmd = self._desired_roll(obs, t)
            omega_des = self._desired_omega(t)
            phi_v, theta_v, lengths = self._rods(obs, omega_des)
            values = (
                t,
                self.roll_des,
                obs.roll_rad,
                omega_des,
                obs.omega_rad_s,
                phi_v,
                theta_v,
                obs.phase_rad,
                k_cmd,
                obs.x,
                obs.y,
                obs.yaw,
                self.s_sim,
                e_lat,
            )
            for key, value in zip(_SCHEDULE_KEYS, values, strict=True):
                self.rec[key].append(float(value))
            self.rec["rod_length_m"].append([float(v) for v in lengths])
            if isinstance(self.sphere, MujocoSphere):
                self.rec["rod_measured_m"].append([float(v) for v in self.sphere.sim.rod_lengths_m()])
                self.rec["rods_on_ground"].append(int(self.sphere.sim.rods_on_ground().sum()))
            if self.s_sim >= self.s_goal:
                self.reached = True
                break
            self.sphere.step(phi_v, theta_v, lengths, self.dt)
            self.obs = self.sphere.observe()
            self._advance_along_path(obs, yawr)

    def _desired_roll(self, obs: Observation, t: float) -> tuple[float, float, float]:
        """Step 1: path curvature (+ tracking correction) → desired roll, rate-limited; (ψ_ref, e_lat, κ_cmd)."""
        ref, tracking = self.ref, self.tracking
        v_plan = ref.v_at_t(ref.t[0] + t)
        xr, yr, yawr = ref.pose_at(self.s_sim)
        e_lat = -(obs.x - xr) * math.sin(yawr) + (obs.y - yr) * math.cos(yawr)
        self.max_lat = max(self.max_lat, abs(e_lat))
        k_ff = ref.curvature_at(self.s_sim + max(v_plan, 0.05) * tracking.lookahead_s)
        k_cmd = k_ff + tracking.k_heading_per_m * wrap(yawr - obs.yaw) - tracking.k_lateral_per_m2 * e_lat
        k_cmd = max(-self.max_k, min(self.max_k, k_cmd))
        target_roll = max(-self.max_roll, min(self.max_roll, float(self.profile.roll_model.roll_for_curvature(k_cmd))))
        step_roll = self.profile.max_roll_rate_rad_s * self.dt
        self.roll_des += max(-step_roll, min(step_roll, target_roll - self.roll_des))
        return yawr, e_lat, k_cmd

    def _desired_omega(self, t: float) -> float:
        """Step 2: the plan's timing (+ progress correction) → desired rolling rate ω."""
        ref = self.ref
        t_plan = ref.t[0] + t
        v_des = ref.v_at_t(t_plan) + self.tracking.k_progress_per_s * (ref.s_at_t(t_plan) - self.s_sim)
        omega_des = max(0.0, min(self.max_omega, v_des / self.params.r_m))
        return 0.0 if self.s_sim >= self.s_goal else omega_des

    def _rods(self, obs: Observation, omega_des: float) -> tuple[float, float, np.ndarray]:
        """Steps 3–4: controllers → plane angles → rod lengths (or the simple driver and its equivalent plane)."""
        if self.driver == "vpip":
            phi_v = self.roll_ctl.command(obs.roll_rad, self.roll_des)
            theta_v = self.pitch_ctl.command(obs.omega_rad_s, omega_des)
            self.vpip.step(phi_v, theta_v, obs.roll_rad, obs.phase_rad)
            return phi_v, theta_v, self.vpip.lengths_m
        targets = self.simple.step(obs.roll_rad, self.roll_des, obs.phase_rad).length_m
        phi_v, theta_v = equivalent_plane(
            self.params,
            targets,
            obs.roll_rad,
            obs.phase_rad,
            (self.roll_gains.output_limit, self.pitch_gains.output_limit),
        )
        return phi_v, theta_v, self.simple.lengths_m

    def _advance_along_path(self, before: Observation, yawr: float) -> None:
        """Progress along the path: the MuJoCo centre's displacement along the tangent, or the surrogate's r·ω."""
        if isinstance(self.sphere, MujocoSphere):
            ds = (self.obs.x - before.x) * math.cos(yawr) + (self.obs.y - before.y) * math.sin(yawr)
            self.s_sim += max(ds, 0.0)
        else:
            self.s_sim += max(before.omega_rad_s * self.profile.radius_m, 0.0) * self.dt

    def summary(self) -> dict[str, Any]:
        rec, dt, params = self.rec, self.dt, self.params
        lengths_arr = np.asarray(rec["rod_length_m"])
        rod_rate = float(np.max(np.abs(np.diff(lengths_arr, axis=0))) / dt) if len(lengths_arr) > 1 else 0.0
        roll_err = np.asarray(rec["roll_rad"]) - np.asarray(rec["roll_desired_rad"])
        gx, gy, _ = self.ref.pose_at(self.s_goal)
        lat = np.asarray(rec["lateral_error_m"])
        summary: dict[str, Any] = {
            "plant": self.plant,
            **setting_names(self.profile),
            "reached_end": self.reached,
            "duration_s": rec["t"][-1],
            "plan_duration_s": self.t_end,
            "ticks": len(rec["t"]),
            "path_length_m": self.ref.length_m,
            "max_lateral_error_m": self.max_lat,
            "rms_lateral_error_m": float(np.sqrt(np.mean(lat**2))),
            "final_position_error_m": math.hypot(self.obs.x - gx, self.obs.y - gy),
            "rms_roll_error_rad": float(np.sqrt(np.mean(roll_err**2))),
            "max_rod_rate_m_s": rod_rate,
            "max_abs_phi_vpip_rad": float(np.max(np.abs(rec["phi_vpip_rad"]))),
            "max_abs_theta_vpip_rad": float(np.max(np.abs(rec["theta_vpip_rad"]))),
        }
        if isinstance(self.sphere, MujocoSphere):
            summary["measured_rod_rate"] = rod_rate_stats(np.asarray(rec["rod_measured_m"]), dt, params.rod_speed_m_s)
            summary["peak_rod_speed_m_s"] = self.sphere.sim.peak_rod_speed_m_s
            summary["max_rod_length_m"] = float(np.max(rec["rod_measured_m"]))
            summary["mean_rods_on_ground"] = float(np.mean(rec["rods_on_ground"]))
        return summary
