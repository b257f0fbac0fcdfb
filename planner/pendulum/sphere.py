"""The dynamic sphere for the closed loop: the eq. 16–19 plant driven by LMPC (speed) and RSLQR (roll).

Paper 001's control chain is plan → instruction-planning MPC (eq. 15: wheel speed and roll commands)
→ motion controllers (eq. 20–32: motor torques) → robot. :class:`DynamicSphere` is the last two links:
given the commands (v, φ) of one control period it runs the LMPC speed controller and the RSLQR roll
controller on the plant's measured state and integrates the plant (:mod:`planner.pendulum.dynamics`)
over the period. It has the interface of the kinematic
:class:`~planner.closed_loop.simulator.SphereSimulator` (``step(state, v_cmd, roll_cmd, dt,
ground_factor)`` → new :class:`SphereState` and the wheel distance), so ``simulate_plan(...,
SimulationOptions(model="dynamic"))`` rolls a plan on it unchanged; it keeps the full plant state
itself (start it with :meth:`reset`).

The inner controllers measure the plant state exactly (encoders and IMU at the motor controller are
assumed clean; the odometry/GNSS disturbances of the outer loop still apply). They run at the outer
loop's period (50 Hz by default, paper 001 §5).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from planner.errors import InvalidInput
from planner.kinematics import SphereState
from planner.pendulum.dynamics import (
    IA,
    IB,
    IPHI,
    ITH,
    IV,
    IX,
    IY,
    PendulumSpherePlant,
    params_from_profile,
)
from planner.pendulum.lmpc import LMPCSettings, LMPCSpeedController
from planner.pendulum.rslqr import RSLQRRollController, RSLQRSettings
from planner.robot import RobotProfile


@dataclass(frozen=True)
class DynamicStep:
    """One control period: the new state, the wheel distance (m) and the motor torques applied (N m)."""

    state: SphereState
    wheel_distance_m: float
    tau_pitch: float
    tau_roll: float


class DynamicSphere:
    """The pendulum-sphere plant with its LMPC and RSLQR motion controllers, one period per :meth:`step`."""

    def __init__(
        self,
        robot: RobotProfile,
        dt_s: float,
        floor: str | None = None,
        substeps: int = 4,
        lmpc: LMPCSettings | None = None,
        rslqr: RSLQRSettings | None = None,
    ) -> None:
        if not (dt_s > 0 and np.isfinite(dt_s)):
            raise InvalidInput("control_rate_hz", "must be a finite number > 0")
        self.robot = robot
        self.params = params_from_profile(robot)
        self.plant = PendulumSpherePlant(self.params, floor)
        self.dt_s = dt_s
        self.substeps = max(1, int(substeps))
        base_l = lmpc or LMPCSettings()
        base_r = rslqr or RSLQRSettings()
        self.speed = LMPCSpeedController(self.params, LMPCSettings(**{**base_l.__dict__, "ts_s": dt_s}))
        self.roll = RSLQRRollController(self.params, RSLQRSettings(**{**base_r.__dict__, "ts_s": dt_s}))
        self.s = np.zeros(11)
        self.solve_ms: list[float] = []
        self.max_pitch_rad = 0.0
        self.max_pendulum_roll_rad = 0.0

    def reset(self, x: float, y: float, yaw: float, roll: float = 0.0, v: float = 0.0) -> None:
        """Start at pose (x, y, yaw), roll φ and speed v with the pendulum at its steady pitch for v."""
        self.s = self.plant.rolling_state(v, x, y, yaw)
        self.s[IPHI] = roll
        self.speed.reset()
        self.roll.reset()
        self.solve_ms = []
        self.max_pitch_rad = abs(float(self.s[IA]))
        self.max_pendulum_roll_rad = 0.0

    @property
    def snapshot(self) -> SphereState:
        s = self.s
        return SphereState(float(s[IX]), float(s[IY]), float(s[ITH]), float(s[IPHI]), float(s[IV]))

    def step(
        self, state: SphereState, v_cmd: float, roll_cmd: float, dt_s: float, ground_factor: float = 1.0
    ) -> DynamicStep:
        """Run both controllers on the measured plant state and integrate one period of ``dt_s``.

        ``state`` is accepted for interface compatibility with the kinematic simulator and ignored: the
        dynamic sphere carries its own full state.
        """
        if abs(dt_s - self.dt_s) > 1e-9:
            raise InvalidInput("dt_s", f"the dynamic sphere was built for {self.dt_s} s periods, got {dt_s}")
        s = self.s
        tau_p = self.speed.step(s[0:4], v_cmd)
        self.solve_ms.append(self.speed.last_solve_ms)
        tau_r = self.roll.step(s[4:8], roll_cmd, float(s[IV]))
        x_c0 = float(s[2])
        self.s = self.plant.step(s, tau_p, tau_r, dt_s, self.substeps, ground_factor)
        self.max_pitch_rad = max(self.max_pitch_rad, abs(float(self.s[IA])))
        self.max_pendulum_roll_rad = max(self.max_pendulum_roll_rad, abs(float(self.s[IB])))
        return DynamicStep(self.snapshot, float(self.s[2]) - x_c0, tau_p, tau_r)


__all__ = ["DynamicSphere", "DynamicStep", "SphereState"]
