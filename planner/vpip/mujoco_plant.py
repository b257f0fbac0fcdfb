"""The DAEDALUS sphere in MuJoCo as a plant for the VPIP cascade (paper 000 §4–5, Fig. 5 "IMU feedback").

Paper 000 closes its controllers (Fig. 5) on the robot's measured roll φ_r and rotational speed ω and
drives the 16 rods with the eq. 18 lengths; §5 runs this on a Gazebo model. :class:`MujocoPlant` is that
loop's plant here: it takes the 16 commanded rod lengths every control tick (100 Hz, Table 1), moves each
rod's reference linearly across the tick and, every physics step, asks the rod's velocity servo for the
reference's rate plus a correction of any lag, clipped to ``±rod_speed_m_s`` (so the plant itself never
drives a rod faster than Table 1's 0.1 m/s; the driver has already rate-limited the lengths), and steps
MuJoCo; :meth:`MujocoPlant.observe` reads what an IMU and
odometry would give: roll, rolling rate ω, pitch phase (how far the sphere has rolled, which sets every
rod's ζ) and the planar pose.

Reading the attitude (body frame as in :mod:`planner.vpip.mujoco_model`): the body orientation is
decomposed as ``R = R_z(ψ − π/2) · R_y(−roll) · R_x(−phase)``, i.e. the paper's eq. 9/12 body
``R_y(φ_r)·R_x(−ζ-offset)`` with φ_r = −roll, turned to the heading ψ. So ``roll = asin(a_z)`` where ``a``
is the axle (body x) in the world, > 0 when the left disc is lower (docs/contracts.md); the heading ψ is
that of the horizontal forward direction; the pitch phase is unwrapped across ±π. The rolling rate is the
gyro's rate about the axle, ``ω = −Ω_x`` (body-frame angular velocity, x is the axle) (> 0 rolling forward).
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from planner.errors import InvalidInput
from planner.vpip.mujoco_model import BodyParams, build_mjcf
from planner.vpip.rods import RodParams

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class Observation:
    """What the controllers see: roll (rad, > 0 left), ω (rad/s), pitch phase (rad), pose (m, rad)."""

    roll_rad: float
    omega_rad_s: float
    phase_rad: float
    x: float
    y: float
    yaw: float


def _import_mujoco() -> Any:
    from planner.extras import require

    return require("mujoco", "plant", "the mujoco plant")


def attitude(xmat: np.ndarray) -> tuple[float, float, float]:
    """(roll, heading ψ, phase in (−π, π]) from a body rotation matrix (row-major 3×3 or 9 values)."""
    r = np.asarray(xmat, dtype=float).reshape(3, 3)
    roll = math.asin(max(-1.0, min(1.0, float(r[2, 0]))))
    heading = math.atan2(float(r[1, 0]), float(r[0, 0])) + 0.5 * math.pi
    phase = -math.atan2(float(r[2, 1]), float(r[2, 2]))
    return roll, math.atan2(math.sin(heading), math.cos(heading)), phase


def orientation_quat(yaw: float, roll: float = 0.0, phase: float = 0.0) -> np.ndarray:
    """MuJoCo quaternion (w, x, y, z) of ``R_z(yaw − π/2)·R_y(−roll)·R_x(−phase)``."""

    def q(axis: int, angle: float) -> np.ndarray:
        out = np.zeros(4)
        out[0] = math.cos(0.5 * angle)
        out[1 + axis] = math.sin(0.5 * angle)
        return out

    def mul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
        w1, x1, y1, z1 = a
        w2, x2, y2, z2 = b
        return np.array(
            [
                w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2,
                w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
                w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2,
                w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2,
            ]
        )

    return mul(mul(q(2, yaw - 0.5 * math.pi), q(1, -roll)), q(0, -phase))


class MujocoPlant:
    """The rod-driven sphere in MuJoCo, stepped one control tick at a time.

    ``x, y, yaw`` place the sphere (resting on the floor, rods retracted, upright); ``settle_s`` lets it
    come to rest before the first tick.
    """

    def __init__(
        self,
        params: RodParams,
        body: BodyParams,
        x: float = 0.0,
        y: float = 0.0,
        yaw: float = 0.0,
        settle_s: float = 0.2,
    ) -> None:
        mujoco = _import_mujoco()
        self._mj = mujoco
        self.params = params
        self.body = body
        self.xml = build_mjcf(params, body)
        self.model = mujoco.MjModel.from_xml_string(self.xml)
        self.data = mujoco.MjData(self.model)
        m = self.model
        self._body_id = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, "sphere")
        n = params.n_rods
        self._rod_qpos = np.array(
            [m.jnt_qposadr[mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, f"rod{i}")] for i in range(n)]
        )
        self._rod_qvel = np.array(
            [m.jnt_dofadr[mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, f"rod{i}")] for i in range(n)]
        )
        self._tip_sites = np.array([mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_SITE, f"tip{i}") for i in range(n)])
        self._tip_geoms = {mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, f"tip{i}"): i for i in range(n)}
        self._floor = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, "floor")
        self.data.qpos[0:3] = (x, y, params.r_m)
        self.data.qpos[3:7] = orientation_quat(yaw)
        self.data.ctrl[:] = 0.0
        mujoco.mj_forward(m, self.data)
        self._phase = 0.0
        self._last_wrapped_phase = 0.0
        self._ctrl = np.zeros(n)
        self.peak_rod_speed_m_s = 0.0
        if settle_s > 0:
            self._advance(np.zeros(n), settle_s)
        self.time_offset_s = float(self.data.time)
        self.peak_rod_speed_m_s = 0.0

    # ----------------------------------------------------------------- state
    @property
    def time_s(self) -> float:
        return float(self.data.time) - self.time_offset_s

    def rod_lengths_m(self) -> np.ndarray:
        return np.array(self.data.qpos[self._rod_qpos], dtype=float)

    def rod_speeds_m_s(self) -> np.ndarray:
        return np.array(self.data.qvel[self._rod_qvel], dtype=float)

    def tip_positions(self) -> np.ndarray:
        """World positions of the 16 rod tips (m), shape ``(2n, 3)``."""
        return np.array(self.data.site_xpos[self._tip_sites], dtype=float)

    def rods_on_ground(self) -> np.ndarray:
        """Boolean ``(2n,)``: which rod tips touch the floor now."""
        out = np.zeros(self.params.n_rods, dtype=bool)
        for c in self.data.contact[: self.data.ncon]:
            for g, other in ((c.geom1, c.geom2), (c.geom2, c.geom1)):
                if other == self._floor and g in self._tip_geoms:
                    out[self._tip_geoms[g]] = True
        return out

    def foot_contacts(self) -> list[tuple[int, np.ndarray, np.ndarray, float]]:
        """Rod feet on the floor now: (rod index, contact point, force on the robot, slip speed) per contact.

        Point and force (N) are in the world frame; the slip speed (m/s) is the horizontal velocity of the
        foot's material point at the contact (0 for a foot that holds).
        """
        mujoco = self._mj
        m, d = self.model, self.data
        out = []
        f6 = np.zeros(6)
        vel = np.zeros(6)
        for i in range(d.ncon):
            c = d.contact[i]
            if c.geom1 == self._floor and c.geom2 in self._tip_geoms:
                g, sign = c.geom2, 1.0
            elif c.geom2 == self._floor and c.geom1 in self._tip_geoms:
                g, sign = c.geom1, -1.0
            else:
                continue
            mujoco.mj_contactForce(m, d, i, f6)
            frame = np.asarray(c.frame, dtype=float).reshape(3, 3)
            force = sign * (frame.T @ f6[:3])  # the force geom1 exerts on geom2, turned onto the foot
            mujoco.mj_objectVelocity(m, d, mujoco.mjtObj.mjOBJ_GEOM, g, vel, 0)
            pos = np.array(c.pos, dtype=float)
            point = vel[3:] + np.cross(vel[:3], pos - d.geom_xpos[g])
            out.append((self._tip_geoms[g], pos, force, float(math.hypot(point[0], point[1]))))
        return out

    def world_angular_velocity(self) -> np.ndarray:
        """The sphere's angular velocity in the world frame (rad/s), shape ``(3,)``."""
        rot = np.asarray(self.data.xmat[self._body_id], dtype=float).reshape(3, 3)
        return np.asarray(rot @ self.data.qvel[3:6], dtype=float)

    def turn_rates(self) -> tuple[float, float]:
        """The heading rate split into (spin Ω_z, tilt term ω_h·tan(roll)) in rad/s, > 0 turning left.

        Kinematics of the axle ``a`` (body x) under ``ȧ = Ω × a``: its heading turns at
        ``ψ̇ = Ω_z − a_z·(Ω·a_h)/|a_h|²`` (``a_h`` its horizontal part), i.e. the spin about the contact
        normal plus ``ω_h·tan(roll)``, ``ω_h = −Ω·a_h/|a_h|`` the rolling rate about the horizontal axle.
        With no spin and no slip (speed r·ω_h) the circle is ``r / tan(roll)``: nothing a rod does can roll
        a tighter circle at a given held roll unless the sphere spins (docs/vpip.md).
        """
        w = self.world_angular_velocity()
        a = np.asarray(self.data.xmat[self._body_id], dtype=float).reshape(3, 3)[:, 0]
        h2 = float(a[0] ** 2 + a[1] ** 2)
        tilt = -float(a[2]) * float(w[0] * a[0] + w[1] * a[1]) / h2 if h2 > 1e-12 else 0.0
        return float(w[2]), tilt

    def observe(self) -> Observation:
        d = self.data
        xmat = d.xmat[self._body_id]
        roll, yaw, wrapped = attitude(xmat)
        delta = math.remainder(wrapped - self._last_wrapped_phase, 2.0 * math.pi)
        self._phase += delta
        self._last_wrapped_phase = wrapped
        omega = -float(d.qvel[3])  # free joint: angular velocity in the body frame, x is the axle
        return Observation(roll, omega, self._phase, float(d.qpos[0]), float(d.qpos[1]), yaw)

    # ------------------------------------------------------------- stepping
    def _advance(self, target: np.ndarray, duration_s: float) -> None:
        """Move every rod's reference linearly to ``target`` over ``duration_s`` and step MuJoCo.

        Each physics step the rod servos get the velocity ``ref_rate + (ref − q) / rod_servo_tracking_s``
        clipped to ``±rod_speed_m_s`` (the actuators' control range): a rod follows its reference and
        makes up any lag, but never faster than Table 1's extension speed.
        """
        mujoco = self._mj
        steps = max(1, round(duration_s / self.model.opt.timestep))
        start = self._ctrl.copy()
        rate = (target - start) / (steps * self.model.opt.timestep)
        vmax = self.params.rod_speed_m_s
        gain = 1.0 / self.body.rod_servo_tracking_s
        for i in range(1, steps + 1):
            ref = start + (target - start) * (i / steps)
            q = self.data.qpos[self._rod_qpos]
            self.data.ctrl[:] = np.clip(rate + gain * (ref - q), -vmax, vmax)
            mujoco.mj_step(self.model, self.data)
            speed = float(np.max(np.abs(self.data.qvel[self._rod_qvel])))
            self.peak_rod_speed_m_s = max(self.peak_rod_speed_m_s, speed)
        self._ctrl = target.copy()

    def step(self, rod_lengths_m: np.ndarray, dt_s: float) -> None:
        """Drive the rod servos toward ``rod_lengths_m`` (linearly over ``dt_s``) and advance ``dt_s``."""
        target = np.clip(np.asarray(rod_lengths_m, dtype=float), 0.0, self.params.l_max)
        if target.shape != (self.params.n_rods,):
            raise InvalidInput("rod_lengths_m", f"needs shape ({self.params.n_rods},), got {target.shape}")
        self._advance(target, dt_s)
        if not np.all(np.isfinite(self.data.qpos)):
            raise FloatingPointError("MuJoCo state became non-finite")
