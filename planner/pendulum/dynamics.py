"""The pendulum sphere's dynamic model: paper 001 §5.1, eq. 16–19, derived here and checked by tests.

Paper 001 builds its motion control on an Euler–Lagrange model (eq. 16) written as M(q)q̈ + N(q, q̇) = Eτ
(eq. 17) and split into a pitch sub-model (eq. 18, pendulum pitch α and shell motion x_c, main motor
torque τ_p) and a roll sub-model (eq. 19, pendulum roll β and robot roll φ, auxiliary motor torque τ_r).
The printed eq. 17 cannot be used as is: its φ is the robot's roll in eq. 1 but the shell's rotation in
Table 7 (x_c = φ r), the pitch inertia matrix is not symmetric (m_p l cos α above the diagonal,
m_p r l cos α below), and the damping terms carry stray cosines. What is implemented is derived below;
the tests check it (energy is conserved without damping and actuation, motor work equals the energy
change, the linearisation matches finite differences of this model, both linear models are
controllable).

Derivation. Each sub-model is a planar "pendulum inside a rolling shell": a shell angle s rolling
without slip (centre displacement r·s) and a pendulum hinged at the centre whose centre of mass sits at
distance l, at absolute angle a from the downward vertical. With a > 0 swinging the pendulum forward
(pitch) or to the left (roll) and s > 0 rolling the shell forward (pitch: x_c = r s) or to the left
(roll: s = φ, the robot's roll of eq. 1, whose lateral shell motion is r φ̇), the motor sits between the
pendulum and the shell and turns them *relative to each other* by a + s; its torque τ therefore does
virtual work τ(δa + δs), which is eq. 17's E = [1 1]ᵀ. The kinetic energy is::

    T = ½ J_a ȧ² + m_p r l cos a · ȧ ṡ + ½ J_s ṡ²
    J_a = m_p l² + I_p (+ I_f in pitch: the frame pitches with the pendulum)
    J_s = m r² + I_s   (+ I_f in roll: the frame and main axis roll with the shell), m = m_s + m_f + m_p

and Euler–Lagrange gives, for each sub-model (the symmetric form of eq. 18/19)::

    [ J_a            m_p r l cos a ] [ä]   [ τ − ∂V/∂a − ζ(ȧ + ṡ)                          ]
    [ m_p r l cos a  J_s           ] [s̈] = [ τ − ζ(ȧ + ṡ) + m_p r l ȧ² sin a − r F_f + Q_Ω ]

with one pendulum potential V = −m_p g l cos α cos β for both (so the pitch row has eq. 17's
m_p g l sin α cos β and the roll row m_p g l cos α sin β, which eq. 17 shortens to sin β), the Rayleigh
dissipation Ψ = ½ ζ (ȧ + ṡ)² of the motor's gearbox on the relative rate, and the rolling resistance F_f
(the smooth Coulomb law c_rr m g · u / √(|u|² + ε²) on the centre's planar velocity u = (ẋ_c, r φ̇); eq.
17's F_f r).

The yaw coupling Q_Ω is not in eq. 17 (the paper decouples pitch and roll and compensates with the
velocity feed-forward ρ of eq. 31, "more centripetal force is required at higher velocity"). While the
robot turns at θ̇ = Ω = v tan φ / r (eq. 1), the body axes rotate, so every mass's body-axis velocity
(u_x, u_y) picks up the transport terms m Ω u_y (forward) and −m Ω u_x (sideways), and the shell's spin
the gyroscopic terms I_s Ω φ̇ and −I_s Ω ṡ_p. Applied to the centre masses (shell, frame) and the
pendulum (at its own body-axis velocity) they form a skew pair that does no work, so the total energy
is still conserved (tested); at speed they pull the roll back to zero, which is why a larger roll is
harder to reach and hold at higher speed (paper 001 §6.7). Ω × (pendulum offset) terms of order Ω l
are neglected.

State (11): α, α̇, x_c, ẋ_c (= v, the wheel speed), β, β̇, φ, φ̇, and the planar pose x, y, θ of eq. 1
(ẋ = v cos θ − r φ̇ sin θ, ẏ = v sin θ + r φ̇ cos θ, θ̇ = v tan φ / r). A slip factor scales the ground
speed in the pose equations only (the shell dynamics are those of rolling without slip).

Parameters come from the profile's ``[dynamics]`` table (planner/robots/zju-*.toml, each number with
its source); :func:`params_from_profile` reads and validates it.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
from scipy.linalg import expm

from planner.errors import InvalidInput, RobotProfileError
from planner.robot import RobotProfile

G = 9.81
"""Gravity (m/s²)."""

STATE_NAMES = ("alpha", "alpha_dot", "x_c", "v", "beta", "beta_dot", "phi", "phi_dot", "x", "y", "yaw")
"""Order of the plant's state vector."""

IA, IAD, IXC, IV, IB, IBD, IPHI, IPHID, IX, IY, ITH = range(11)


@dataclass(frozen=True)
class PendulumParams:
    """Physical parameters of one pendulum sphere (SI units); see the module docstring for the model.

    ``rolling_resistance`` maps a floor name (``tiled``, ``rubber``) to its coefficient c_rr;
    ``nominal_floor`` is the floor the controllers' models assume. ``max_speed_m_s`` bounds the
    controller experiments (not the planner's cruise speed). ``max_pendulum_angle_rad`` is paper 001
    §5.1's bound on the pendulum's swing (15°), which keeps the linearisation valid; the LMPC keeps the
    pitch α within it.
    """

    radius_m: float
    shell_mass_kg: float
    shell_inertia_kg_m2: float
    frame_mass_kg: float
    frame_inertia_pitch_kg_m2: float
    frame_inertia_roll_kg_m2: float
    pendulum_mass_kg: float
    pendulum_length_m: float
    pendulum_inertia_pitch_kg_m2: float
    pendulum_inertia_roll_kg_m2: float
    damping_pitch_n_m_s: float
    damping_roll_n_m_s: float
    rolling_resistance: Mapping[str, float] = field(default_factory=lambda: {"tiled": 0.02})
    nominal_floor: str = "tiled"
    rolling_speed_eps_m_s: float = 0.05
    max_torque_pitch_n_m: float = 12.0
    max_torque_roll_n_m: float = 8.0
    max_speed_m_s: float = 2.0
    max_pendulum_angle_rad: float = math.radians(15.0)

    @property
    def total_mass_kg(self) -> float:
        return self.shell_mass_kg + self.frame_mass_kg + self.pendulum_mass_kg

    @property
    def coupling(self) -> float:
        """m_p r l, the off-diagonal inertia at a = 0 (kg m²)."""
        return self.pendulum_mass_kg * self.radius_m * self.pendulum_length_m

    @property
    def gravity_torque_n_m(self) -> float:
        """m_p g l: the largest torque gravity can hold on the pendulum (pendulum horizontal)."""
        return self.pendulum_mass_kg * G * self.pendulum_length_m

    def inertias(self, sub: str) -> tuple[float, float]:
        """(J_a, J_s) of the ``"pitch"`` or ``"roll"`` sub-model."""
        mp, l, r = self.pendulum_mass_kg, self.pendulum_length_m, self.radius_m
        if sub == "pitch":
            return (
                mp * l * l + self.pendulum_inertia_pitch_kg_m2 + self.frame_inertia_pitch_kg_m2,
                self.total_mass_kg * r * r + self.shell_inertia_kg_m2,
            )
        if sub == "roll":
            return (
                mp * l * l + self.pendulum_inertia_roll_kg_m2,
                self.total_mass_kg * r * r + self.shell_inertia_kg_m2 + self.frame_inertia_roll_kg_m2,
            )
        raise InvalidInput("sub", f"must be 'pitch' or 'roll', got {sub!r}")

    def damping(self, sub: str) -> float:
        return self.damping_pitch_n_m_s if sub == "pitch" else self.damping_roll_n_m_s

    def floor_coefficient(self, floor: str | None) -> float:
        """c_rr of ``floor`` (None = the nominal floor)."""
        name = self.nominal_floor if floor is None else floor
        if name not in self.rolling_resistance:
            known = ", ".join(sorted(self.rolling_resistance))
            raise InvalidInput("floor", f"unknown floor {name!r}; this robot knows: {known}")
        return float(self.rolling_resistance[name])

    def max_torque(self, sub: str) -> float:
        return self.max_torque_pitch_n_m if sub == "pitch" else self.max_torque_roll_n_m


_POSITIVE = (
    "shell_mass_kg", "shell_inertia_kg_m2", "frame_mass_kg", "frame_inertia_pitch_kg_m2",
    "frame_inertia_roll_kg_m2", "pendulum_mass_kg", "pendulum_length_m", "pendulum_inertia_pitch_kg_m2",
    "pendulum_inertia_roll_kg_m2", "rolling_speed_eps_m_s", "max_torque_pitch_n_m", "max_torque_roll_n_m",
    "max_speed_m_s",
)
_NON_NEGATIVE = ("damping_pitch_n_m_s", "damping_roll_n_m_s")


def _number(section: Mapping[str, Any], key: str, positive: bool) -> float:
    if key not in section:
        raise RobotProfileError(f"dynamics.{key}", "is required")
    value = section[key]
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(float(value)):
        raise RobotProfileError(f"dynamics.{key}", f"must be a finite number, got {value!r}")
    if (positive and value <= 0) or value < 0:
        raise RobotProfileError(f"dynamics.{key}", f"must be {'> 0' if positive else '>= 0'}, got {value!r}")
    return float(value)


def params_from_profile(robot: RobotProfile) -> PendulumParams:
    """The ``[dynamics]`` table of ``robot`` as :class:`PendulumParams` (errors name ``dynamics.<key>``)."""
    section = robot.extra.get("dynamics")
    if not isinstance(section, Mapping):
        raise RobotProfileError("dynamics", f"robot {robot.name!r} has no [dynamics] table (pendulum spheres only)")
    values = {k: _number(section, k, True) for k in _POSITIVE}
    values.update({k: _number(section, k, False) for k in _NON_NEGATIVE})
    floors = section.get("rolling_resistance")
    if not isinstance(floors, Mapping) or not floors:
        raise RobotProfileError("dynamics.rolling_resistance", "must be a table floor = coefficient")
    coeffs = {str(k): _number(floors, k, False) for k in floors}
    nominal = section.get("nominal_floor", next(iter(coeffs)))
    if nominal not in coeffs:
        raise RobotProfileError("dynamics.nominal_floor", f"{nominal!r} is not in rolling_resistance")
    angle = math.radians(_number(section, "max_pendulum_angle_deg", True))
    if angle >= math.pi / 2:
        raise RobotProfileError("dynamics.max_pendulum_angle_deg", "must be below 90")
    params = PendulumParams(
        radius_m=robot.radius_m,
        rolling_resistance=coeffs,
        nominal_floor=str(nominal),
        max_pendulum_angle_rad=angle,
        **values,
    )
    if params.pendulum_length_m >= params.radius_m:
        raise RobotProfileError("dynamics.pendulum_length_m", "must be shorter than the shell radius")
    return params


@dataclass(frozen=True)
class LinearModel:
    """ẋ = A x + B u + V of one sub-model linearised at rest (paper 001 eq. 20), in the paper's states.

    pitch: x = (α, α̇, x_c, ẋ_c), u = τ_p; roll: x = (β, β̇, φ, φ̇), u = τ_r. ``V`` is the constant
    rolling resistance F_f of forward travel (eq. 20's V_c; zero for roll, which rolls sideways only
    transiently). ``m_inv`` is the inverse of the linearised inertia matrix in (a, s) coordinates
    (eq. 30's M_rL⁻¹).
    """

    sub: str
    a: np.ndarray
    b: np.ndarray
    v: np.ndarray
    m_inv: np.ndarray

    def discretise(self, ts_s: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Exact zero-order-hold discretisation (A_d, B_d, V_d) over ``ts_s``.

        Paper 001 eq. 21 uses forward Euler (A_d = I + A_c T_s); at 50 Hz that makes the undamped
        pendulum mode grow (|1 + iωT_s| > 1), so the matrix exponential is used instead (tested).
        """
        n = self.a.shape[0]
        big = np.zeros((n + 2, n + 2))
        big[:n, :n] = self.a
        big[:n, n] = self.b
        big[:n, n + 1] = self.v
        e = expm(big * ts_s)
        return e[:n, :n], e[:n, n], e[:n, n + 1]


def linear_model(
    params: PendulumParams, sub: str, floor: str | None = None, forward: float = 1.0, speed: float = 0.0
) -> LinearModel:
    """Linearise the ``"pitch"`` or ``"roll"`` sub-model at rest (a = ȧ = ṡ = 0, no yaw rate).

    With M_L the inertia matrix at a = 0, K = diag(m_p g l, 0) and D = ζ [[1, 1], [1, 1]] in (a, s)
    coordinates: q̈ = M_L⁻¹ (E u − K q − D q̇ − [0, r F_f]). For pitch, s = x_c / r turns the shell rows
    into metres. ``forward`` (+1, −1, or 0 at rest) is the travel direction the constant F_f opposes.

    ``speed`` v ≠ 0 linearises the roll sub-model about rolling straight at v instead (paper 001 does it
    at rest only): the yaw coupling Ω = v tan φ / r then adds the stiffness (∂/∂φ of Q_Ω) m_p l v²/r on
    the pendulum row and (m + I_s/r²) v² on the shell row, the roll's pull back to upright at speed.
    """
    ja, js = params.inertias(sub)
    c = params.coupling
    m_l = np.array([[ja, c], [c, js]])
    m_inv = np.linalg.inv(m_l)
    k = np.diag([params.gravity_torque_n_m, 0.0])
    if sub == "roll" and speed != 0.0:
        r0 = params.radius_m
        k[0, 1] = params.pendulum_mass_kg * params.pendulum_length_m * speed**2 / r0
        k[1, 1] = (params.total_mass_kg + params.shell_inertia_kg_m2 / r0**2) * speed**2
    zeta = params.damping(sub)
    d = zeta * np.ones((2, 2))
    e = np.array([1.0, 1.0])
    # (a, s, ȧ, ṡ) first, then reorder to the paper's (a, ȧ, s, ṡ)
    a_q = np.zeros((4, 4))
    a_q[0:2, 2:4] = np.eye(2)
    a_q[2:4, 0:2] = -m_inv @ k
    a_q[2:4, 2:4] = -m_inv @ d
    b_q = np.concatenate([np.zeros(2), m_inv @ e])
    r = params.radius_m
    friction = params.floor_coefficient(floor) * params.total_mass_kg * G if sub == "pitch" else 0.0
    v_q = np.concatenate([np.zeros(2), m_inv @ np.array([0.0, -r * friction * float(np.sign(forward))])])
    order = [0, 2, 1, 3]
    p = np.eye(4)[order]  # paper state = p @ (a, s, ȧ, ṡ)
    scale = np.diag([1.0, 1.0, r, r]) if sub == "pitch" else np.eye(4)
    t = scale @ p
    t_inv = np.linalg.inv(t)
    return LinearModel(sub, t @ a_q @ t_inv, t @ b_q, t @ v_q, m_inv)


class PendulumSpherePlant:
    """The nonlinear model of the module docstring, integrated with fixed-step RK4.

    ``floor`` selects the rolling resistance; ``yaw_coupling`` False drops the Q_Ω terms (the paper's
    fully decoupled eq. 18/19). Torques are clipped to the motors' limits in :meth:`step`.
    """

    def __init__(self, params: PendulumParams, floor: str | None = None, yaw_coupling: bool = True) -> None:
        self.p = params
        self.floor = params.nominal_floor if floor is None else floor
        self.c_rr = params.floor_coefficient(self.floor)
        self.yaw_coupling = yaw_coupling
        self._jap, self._jsp = params.inertias("pitch")
        self._jar, self._jsr = params.inertias("roll")

    def without_losses(self) -> PendulumSpherePlant:
        """The same robot with no damping and no rolling resistance (for the energy test)."""
        p = replace(
            self.p,
            damping_pitch_n_m_s=0.0,
            damping_roll_n_m_s=0.0,
            rolling_resistance=dict.fromkeys(self.p.rolling_resistance, 0.0),
        )
        return PendulumSpherePlant(p, self.floor, self.yaw_coupling)

    def rolling_force(self, v: float, v_lat: float) -> tuple[float, float]:
        """Rolling resistance (F_x, F_y) (N) on the centre's planar velocity (v, v_lat)."""
        eps = self.p.rolling_speed_eps_m_s
        scale = self.c_rr * self.p.total_mass_kg * G / math.sqrt(v * v + v_lat * v_lat + eps * eps)
        return scale * v, scale * v_lat

    def rhs(self, s: Sequence[float], tau_p: float, tau_r: float, ground_factor: float = 1.0) -> list[float]:
        """Time derivative of the state ``s`` (11,) under motor torques τ_p, τ_r (N m)."""
        p = self.p
        r, l, mp = p.radius_m, p.pendulum_length_m, p.pendulum_mass_kg
        m, i_s = p.total_mass_kg, p.shell_inertia_kg_m2
        c = mp * r * l
        a, ad, v, b, bd, ph, phd, th = s[IA], s[IAD], s[IV], s[IB], s[IBD], s[IPHI], s[IPHID], s[ITH]
        ca, sa, cb, sb = math.cos(a), math.sin(a), math.cos(b), math.sin(b)
        spd = v / r  # shell pitch rate ṡ_p
        v_lat = r * phd
        fx, fy = self.rolling_force(v, v_lat)
        omega = v * math.tan(ph) / r
        # pitch sub-model: generalised forces on (α, s_p)
        rel_p = p.damping_pitch_n_m_s * (ad + spd)
        qa = tau_p - mp * G * l * sa * cb - rel_p
        qs = tau_p - rel_p + c * ad * ad * sa - r * fx
        # roll sub-model: generalised forces on (β, φ)
        rel_r = p.damping_roll_n_m_s * (bd + phd)
        qb = tau_r - mp * G * l * ca * sb - rel_r
        qph = tau_r - rel_r + c * bd * bd * sb - r * fy
        if self.yaw_coupling and omega != 0.0:
            upx = v + l * ca * ad  # pendulum body-axis velocity
            upy = v_lat + l * cb * bd
            mc = m - mp  # masses at the centre (shell, frame)
            qa += omega * mp * upy * l * ca
            qs += omega * (r * mc * v_lat + r * mp * upy + i_s * phd)
            qb -= omega * mp * upx * l * cb
            qph -= omega * (r * mc * v + r * mp * upx + i_s * spd)
        m12 = c * ca
        det = self._jap * self._jsp - m12 * m12
        add = (self._jsp * qa - m12 * qs) / det
        sdd = (self._jap * qs - m12 * qa) / det
        n12 = c * cb
        det_r = self._jar * self._jsr - n12 * n12
        bdd = (self._jsr * qb - n12 * qph) / det_r
        phdd = (self._jar * qph - n12 * qb) / det_r
        vg = v * ground_factor
        ct, st = math.cos(th), math.sin(th)
        return [
            ad, add, v, r * sdd,
            bd, bdd, phd, phdd,
            vg * ct - v_lat * st, vg * st + v_lat * ct, vg * math.tan(ph) / r,
        ]

    def step(
        self,
        s: np.ndarray,
        tau_p: float,
        tau_r: float,
        dt_s: float,
        substeps: int = 4,
        ground_factor: float = 1.0,
    ) -> np.ndarray:
        """Advance ``s`` by ``dt_s`` holding the (clipped) torques: ``substeps`` RK4 steps."""
        tp = max(-self.p.max_torque_pitch_n_m, min(self.p.max_torque_pitch_n_m, tau_p))
        tr = max(-self.p.max_torque_roll_n_m, min(self.p.max_torque_roll_n_m, tau_r))
        h = dt_s / substeps
        x = [float(v) for v in s]
        f = self.rhs
        for _ in range(substeps):
            k1 = f(x, tp, tr, ground_factor)
            k2 = f([xi + 0.5 * h * ki for xi, ki in zip(x, k1, strict=True)], tp, tr, ground_factor)
            k3 = f([xi + 0.5 * h * ki for xi, ki in zip(x, k2, strict=True)], tp, tr, ground_factor)
            k4 = f([xi + h * ki for xi, ki in zip(x, k3, strict=True)], tp, tr, ground_factor)
            x = [xi + h / 6.0 * (a + 2 * b + 2 * c + d) for xi, a, b, c, d in zip(x, k1, k2, k3, k4, strict=True)]
        return np.array(x)

    def energy(self, s: Sequence[float]) -> float:
        """Kinetic + potential energy (J) of both sub-models (zero at rest with the pendulum down)."""
        p = self.p
        r, l, mp = p.radius_m, p.pendulum_length_m, p.pendulum_mass_kg
        c = mp * r * l
        a, ad, v, b, bd, phd = s[IA], s[IAD], s[IV], s[IB], s[IBD], s[IPHID]
        spd = v / r
        t_p = 0.5 * self._jap * ad * ad + c * math.cos(a) * ad * spd + 0.5 * self._jsp * spd * spd
        t_r = 0.5 * self._jar * bd * bd + c * math.cos(b) * bd * phd + 0.5 * self._jsr * phd * phd
        return t_p + t_r + mp * G * l * (1.0 - math.cos(a) * math.cos(b))

    def power(self, s: Sequence[float], tau_p: float, tau_r: float) -> float:
        """dE/dt predicted by the model: motor work minus gearbox damping and rolling resistance (W)."""
        p = self.p
        rel_p = s[IAD] + s[IV] / p.radius_m
        rel_r = s[IBD] + s[IPHID]
        fx, fy = self.rolling_force(s[IV], p.radius_m * s[IPHID])
        return (
            tau_p * rel_p + tau_r * rel_r - p.damping_pitch_n_m_s * rel_p**2 - p.damping_roll_n_m_s * rel_r**2
            - fx * s[IV] - fy * p.radius_m * s[IPHID]
        )

    def pitch_equilibrium(self, v: float) -> tuple[float, float]:
        """(α, τ_p) that hold a constant speed ``v`` straight ahead on this plant's floor."""
        p = self.p
        fx, _ = self.rolling_force(v, 0.0)
        tau = p.damping_pitch_n_m_s * v / p.radius_m + p.radius_m * fx
        ratio = p.radius_m * fx / p.gravity_torque_n_m  # pendulum row: m_p g l sin α = τ − ζ ṡ = r F_f
        if abs(ratio) >= 1.0:
            raise InvalidInput("speed", f"{v} m/s cannot be held: the pendulum cannot balance the losses")
        return math.asin(ratio), tau

    def rolling_state(self, v: float, x: float = 0.0, y: float = 0.0, yaw: float = 0.0) -> np.ndarray:
        """The plant state rolling straight at ``v`` in equilibrium (pendulum at its steady pitch)."""
        s = np.zeros(11)
        s[IA], _ = self.pitch_equilibrium(v)
        s[IV], s[IX], s[IY], s[ITH] = v, x, y, yaw
        return s


def controllability_rank(a: np.ndarray, b: np.ndarray) -> int:
    """Rank of [B, AB, …, Aⁿ⁻¹B]."""
    n = a.shape[0]
    cols = [b.reshape(n, -1)]
    for _ in range(n - 1):
        cols.append(a @ cols[-1])
    return int(np.linalg.matrix_rank(np.hstack(cols)))


__all__ = [
    "STATE_NAMES",
    "G",
    "LinearModel",
    "PendulumParams",
    "PendulumSpherePlant",
    "controllability_rank",
    "linear_model",
    "params_from_profile",
]
