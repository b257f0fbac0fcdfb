"""Path tracking for the sphere: the instruction-planning MPC of paper 001 §4.2 (eq. 15) and a fallback.

:class:`ReferencePath` splits a plan's ``states`` into forward/reverse segments (at cusps) and gives the
reference along each. :class:`MPCTracker` solves eq. 15 with CasADi by direct multiple shooting:

* state X = (x, y, θ, φ), input U = (v, φ_cmd) (wheel speed m/s, roll command rad);
* dynamics (15a): eq. 1 with the pendulum's first-order roll response φ̇ = (φ_cmd − φ)/τ, RK4 over
  ``dt_s``; (15b) X₀ = the current estimate;
* bounds (15c–d): |φ| ≤ φ_max, |φ_cmd| ≤ φ_max, roll rate |φ_cmd − φ|/τ ≤ φ̇_max, speed in
  [0, v_max] forward or [−v_max, 0] reverse, |Δv| ≤ a_max·dt;
* obstacles (15f): ‖p_i − o_j‖² ≥ (r + r_obj,j + ξ_s)² for the K obstacle envelope circles nearest the
  horizon (:class:`ObstacleCircles`, occupied map cells), softened by one slack per stage with an exact
  L1 penalty (an assumption: an estimate that already sits inside the margin must still give a command);
* cost (15): Σ ‖X_i − X_ref,i‖²_Q + Σ ‖U_i − U_ref,i‖²_R (+ a small ‖ΔU‖² smoothing term, assumption);
* solved by SQP (``sqpmethod``, QP solver ``qrqp`` shipped with CasADi), warm-started from the previous
  solution and multipliers.

When the solver fails, :class:`PurePursuitTracker` gives that step's command and the caller counts it.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from scipy.spatial import cKDTree

from planner.errors import InvalidInput
from planner.kinematics import wrap
from planner.maps.clearance import boundary_cell_centres
from planner.occupancy import OccupancyGrid
from planner.result import state_column
from planner.robot import RobotProfile


@dataclass(frozen=True)
class Estimate:
    """What the tracker knows: estimated pose (m, rad), IMU roll (rad), encoder wheel speed (m/s)."""

    x: float
    y: float
    yaw: float
    roll: float
    v: float


@dataclass(frozen=True)
class Command:
    """A control command: wheel speed (m/s) and roll (rad); ``ok`` False when the tracker failed."""

    v: float
    roll: float
    ok: bool = True
    solve_ms: float = 0.0


class ReferenceSegment:
    """One drive direction of the path: arrays over its own arc length ``s`` (m) from 0.

    Attributes: ``s, x, y, yaw (unwrapped), roll`` (n,), ``direction`` (+1 forward, −1 reverse).
    """

    def __init__(self, xy: np.ndarray, yaw: np.ndarray, roll: np.ndarray, direction: int) -> None:
        steps = np.hypot(*np.diff(xy, axis=0).T) if len(xy) > 1 else np.zeros(0)
        self.s = np.concatenate([[0.0], np.cumsum(steps)])
        self.x, self.y = xy[:, 0].copy(), xy[:, 1].copy()
        self.yaw = np.unwrap(yaw)
        self.roll = roll.copy()
        self.direction = direction

    @property
    def length_m(self) -> float:
        return float(self.s[-1])

    def sample(self, s: np.ndarray | float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(x, y, yaw, roll) at arc lengths ``s`` (clamped to the segment)."""
        q = np.clip(np.asarray(s, dtype=float), 0.0, self.length_m)
        return (
            np.interp(q, self.s, self.x),
            np.interp(q, self.s, self.y),
            np.interp(q, self.s, self.yaw),
            np.interp(q, self.s, self.roll),
        )

    def project(self, x: float, y: float, s_hint: float, back_m: float = 0.3, ahead_m: float = 1.5) -> float:
        """Arc length of the point nearest (x, y) among the pieces within [s_hint − back, s_hint + ahead]."""
        if len(self.s) < 2:
            return 0.0
        lo = max(0, int(np.searchsorted(self.s, s_hint - back_m)) - 1)
        hi = min(len(self.s) - 1, int(np.searchsorted(self.s, s_hint + ahead_m)) + 1)
        ax, ay = self.x[lo:hi], self.y[lo:hi]
        bx, by = self.x[lo + 1 : hi + 1], self.y[lo + 1 : hi + 1]
        dx, dy = bx - ax, by - ay
        l2 = dx * dx + dy * dy
        t = np.clip(((x - ax) * dx + (y - ay) * dy) / np.where(l2 > 0, l2, 1.0), 0.0, 1.0)
        d2 = (ax + t * dx - x) ** 2 + (ay + t * dy - y) ** 2
        i = int(np.argmin(d2))
        return float(self.s[lo + i] + t[i] * (self.s[lo + i + 1] - self.s[lo + i]))

    def remaining(self, x: float, y: float) -> float:
        """Signed distance (m) still to roll to the segment's end, along the end heading (≤ 0 = passed)."""
        yaw_end = self.yaw[-1]
        return self.direction * ((self.x[-1] - x) * math.cos(yaw_end) + (self.y[-1] - y) * math.sin(yaw_end))


class ReferencePath:
    """A plan's ``states`` as forward/reverse :class:`ReferenceSegment` s, split at cusps."""

    def __init__(self, states: list[dict[str, Any]]) -> None:
        if not isinstance(states, list) or len(states) < 2:
            raise InvalidInput("path.states", "needs at least two states")
        columns = [state_column(states, key, key in ("x", "y", "yaw")) for key in ("x", "y", "yaw", "roll", "v")]
        arr = np.column_stack([np.zeros(len(states)) if c is None else c for c in columns])
        self.states = arr
        d = np.diff(arr[:, :2], axis=0)
        along = d[:, 0] * np.cos(arr[:-1, 2]) + d[:, 1] * np.sin(arr[:-1, 2])
        step = np.hypot(d[:, 0], d[:, 1])
        # direction of each piece: by motion along the heading; sideways roll shifts and repeats inherit
        direction = np.zeros(len(d), dtype=int)
        moving = np.abs(along) > 0.3 * step
        direction[moving] = np.sign(along[moving]).astype(int)
        vsign = np.sign(arr[:-1, 4]).astype(int)
        direction[~moving] = vsign[~moving]
        last = 1 if not np.any(direction) else int(direction[np.flatnonzero(direction)[0]])
        for i in range(len(direction)):
            if direction[i] == 0:
                direction[i] = last
            last = int(direction[i])
        self.segments: list[ReferenceSegment] = []
        start = 0
        for i in range(1, len(direction) + 1):
            if i == len(direction) or direction[i] != direction[start]:
                idx = slice(start, i + 1)
                self.segments.append(
                    ReferenceSegment(arr[idx, :2], arr[idx, 2], arr[idx, 3], int(direction[start]))
                )
                start = i

    @property
    def end(self) -> np.ndarray:
        """Final (x, y, yaw, roll) of the path."""
        return self.states[-1, :4]

    def polyline(self) -> np.ndarray:
        """All path positions (n, 2)."""
        return self.states[:, :2]


def speed_profile(
    seg: ReferenceSegment, s: np.ndarray | float, cruise_m_s: float, brake_m_s2: float
) -> np.ndarray:
    """Reference speed magnitude (m/s) along ``seg``: ``cruise`` capped so the robot can stop at the end."""
    rem = np.maximum(seg.length_m - np.asarray(s, dtype=float), 0.0)
    return np.minimum(cruise_m_s, np.sqrt(2.0 * brake_m_s2 * rem))


class ObstacleCircles:
    """Obstacle envelope circles of eq. 15f: one circle (centre, radius res/√2) per boundary map cell."""

    def __init__(self, grid: OccupancyGrid) -> None:
        self.centres = boundary_cell_centres(grid)
        self.radius_m = grid.resolution_m / math.sqrt(2.0)
        self._tree = cKDTree(self.centres) if len(self.centres) else None

    def nearby(self, points: np.ndarray, k: int, within_m: float) -> np.ndarray:
        """Up to ``k`` circles (k, 3) = (x, y, r_obj): the nearest cell to each of ``points`` (m, 2), then
        the overall nearest, within ``within_m``; missing rows are far-away dummies (radius 0)."""
        out = np.zeros((k, 3))
        out[:, 0] = 1e2 + points[0, 0]
        out[:, 1] = 1e2 + points[0, 1]
        if self._tree is None:
            return out
        dist, idx = self._tree.query(points, k=1, distance_upper_bound=within_m)
        order = np.argsort(dist)
        chosen: list[int] = []
        for j in order:
            if np.isfinite(dist[j]) and int(idx[j]) not in chosen:
                chosen.append(int(idx[j]))
            if len(chosen) == k:
                break
        for row, c in enumerate(chosen):
            out[row] = (self.centres[c, 0], self.centres[c, 1], self.radius_m)
        return out


@dataclass(frozen=True)
class MPCParams:
    """MPC settings (assumptions with defaults; paper 001 gives the structure, not the numbers).

    horizon : N stages; dt_s : stage length (s); q : weights on (x, y, θ, φ); r : on (v, φ_cmd) deviations;
    r_delta : on input changes; n_obstacles : K envelope circles; safety_margin_m : ξ_s of eq. 15f;
    slack_weight : L1 penalty of the softened eq. 15f; cruise_m_s : reference speed (None = profile max);
    qpsol : CasADi QP solver used by ``sqpmethod``; max_iter : SQP iterations per solve.
    """

    horizon: int = 15
    dt_s: float = 0.1
    q: tuple[float, float, float, float] = (20.0, 20.0, 4.0, 0.2)
    r: tuple[float, float] = (2.0, 2.0)
    r_delta: tuple[float, float] = (1.0, 5.0)
    n_obstacles: int = 6
    safety_margin_m: float = 0.03
    slack_weight: float = 1e3
    cruise_m_s: float | None = None
    qpsol: str = "qrqp"
    max_iter: int = 10
    extra_options: dict[str, Any] = field(default_factory=dict)


class MPCTracker:
    """Eq. 15 of paper 001 as a CasADi multiple-shooting SQP, warm-started step to step."""

    def __init__(
        self, robot: RobotProfile, params: MPCParams | None = None, obstacles: ObstacleCircles | None = None
    ) -> None:
        from planner.extras import require

        ca = require("casadi", "tracker", "the MPC tracker (use --tracker pursuit without it)")
        self.robot = robot
        self.p = params or MPCParams()
        self.obstacles = obstacles
        self.cruise = min(robot.max_speed_m_s, self.p.cruise_m_s or robot.max_speed_m_s)
        self.brake = 0.5 * robot.max_accel_m_s2
        self._warm: dict[str, Any] | None = None
        self._build(ca)

    def _kappa(self, ca: Any, phi: Any) -> Any:
        model = self.robot.roll_model
        if model.kind == "kinematic":
            return ca.tan(phi) / model.radius_m
        # calibrated table: an odd polynomial fitted to κ(φ) over the profile's roll range
        grid = np.linspace(0.0, self.robot.max_roll_rad, 50)
        kap = np.asarray(model.curvature(grid))
        basis = np.stack([grid, grid**3, grid**5], axis=1)
        c = np.linalg.lstsq(basis, kap, rcond=None)[0]
        return c[0] * phi + c[1] * phi**3 + c[2] * phi**5

    def _build(self, ca: Any) -> None:
        p, rob = self.p, self.robot
        n, k_obs, dt = p.horizon, p.n_obstacles, p.dt_s
        tau, r = rob.roll_time_constant_s, rob.radius_m
        xs, us = ca.SX.sym("x", 4), ca.SX.sym("u", 2)
        rate = (us[1] - xs[3]) / tau
        vk = us[0] * self._kappa(ca, xs[3])
        f = ca.Function(
            "f",
            [xs, us],
            [
                ca.vertcat(
                    us[0] * ca.cos(xs[2]) - r * rate * ca.sin(xs[2]),
                    us[0] * ca.sin(xs[2]) + r * rate * ca.cos(xs[2]),
                    vk,
                    rate,
                )
            ],
        )
        k1 = f(xs, us)
        k2 = f(xs + dt / 2 * k1, us)
        k3 = f(xs + dt / 2 * k2, us)
        k4 = f(xs + dt * k3, us)
        step = ca.Function("step", [xs, us], [xs + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)])

        X = ca.SX.sym("X", 4, n + 1)
        U = ca.SX.sym("U", 2, n)
        S = ca.SX.sym("S", n)
        x0 = ca.SX.sym("x0", 4)
        v_prev = ca.SX.sym("v_prev")
        xref = ca.SX.sym("xref", 4, n)
        uref = ca.SX.sym("uref", 2, n)
        obs = ca.SX.sym("obs", 3, k_obs)
        Q, R, Rd = ca.diag(ca.DM(p.q)), ca.diag(ca.DM(p.r)), ca.diag(ca.DM(p.r_delta))
        cost = 0
        g, lbg, ubg = [X[:, 0] - x0], [0.0] * 4, [0.0] * 4
        max_dphi = rob.max_roll_rate_rad_s * tau
        max_dv = rob.max_accel_m_s2 * dt
        for i in range(n):
            g.append(X[:, i + 1] - step(X[:, i], U[:, i]))
            lbg += [0.0] * 4
            ubg += [0.0] * 4
            g.append(U[1, i] - X[3, i])
            lbg.append(-max_dphi)
            ubg.append(max_dphi)
            g.append(U[0, i] - (v_prev if i == 0 else U[0, i - 1]))
            lbg.append(-max_dv)
            ubg.append(max_dv)
            e = X[:, i + 1] - xref[:, i]
            du = U[:, i] - uref[:, i]
            cost += ca.mtimes([e.T, Q, e]) + ca.mtimes([du.T, R, du]) + p.slack_weight * S[i] + S[i] ** 2
            if i > 0:
                dd = U[:, i] - U[:, i - 1]
                cost += ca.mtimes([dd.T, Rd, dd])
            for j in range(k_obs):
                reach = r + obs[2, j] + p.safety_margin_m
                g.append((X[0, i + 1] - obs[0, j]) ** 2 + (X[1, i + 1] - obs[1, j]) ** 2 - reach**2 + S[i])
                lbg.append(0.0)
                ubg.append(ca.inf)
        w = ca.vertcat(ca.reshape(X, -1, 1), ca.reshape(U, -1, 1), S)
        par = ca.vertcat(x0, v_prev, ca.reshape(xref, -1, 1), ca.reshape(uref, -1, 1), ca.reshape(obs, -1, 1))
        opts: dict[str, Any] = {
            "qpsol": p.qpsol,
            "print_time": False,
            "print_header": False,
            "print_iteration": False,
            "print_status": False,
            "max_iter": p.max_iter,
            "error_on_fail": False,
        }
        if p.qpsol == "qrqp":
            opts["qpsol_options"] = {
                "print_iter": False,
                "print_header": False,
                "print_info": False,
                "error_on_fail": False,
            }
        elif p.qpsol == "osqp":
            opts["qpsol_options"] = {"osqp": {"verbose": False}, "error_on_fail": False}
        opts.update(p.extra_options)
        self.solver = ca.nlpsol("mpc", "sqpmethod", {"x": w, "f": cost, "g": ca.vertcat(*g), "p": par}, opts)
        self._lbg, self._ubg = np.array(lbg), np.array(ubg)
        self._nx = 4 * (n + 1)
        self._nu = 2 * n
        inf = np.inf
        lbx = np.concatenate(
            [
                np.tile([-inf, -inf, -inf, -rob.max_roll_rad], n + 1),
                np.tile([-rob.max_speed_m_s, -rob.max_roll_rad], n),
                np.zeros(n),
            ]
        )
        ubx = np.concatenate(
            [
                np.tile([inf, inf, inf, rob.max_roll_rad], n + 1),
                np.tile([rob.max_speed_m_s, rob.max_roll_rad], n),
                np.full(n, inf),
            ]
        )
        self._lbx, self._ubx = lbx, ubx

    def reset(self) -> None:
        """Forget the warm start (a new segment begins)."""
        self._warm = None

    def reference(self, est: Estimate, seg: ReferenceSegment, s0: float) -> tuple[np.ndarray, np.ndarray]:
        """Horizon references: X_ref (4, N) and U_ref (2, N) from arc length ``s0`` at the profile speed."""
        n, dt = self.p.horizon, self.p.dt_s
        s = np.empty(n + 1)
        s[0] = s0
        v = np.empty(n)
        for i in range(n):
            v[i] = float(speed_profile(seg, s[i], self.cruise, self.brake))
            s[i + 1] = s[i] + v[i] * dt
        x, y, yaw, roll = seg.sample(s[1:])
        yaw = yaw + 2 * math.pi * round((est.yaw - yaw[0]) / (2 * math.pi))
        return np.stack([x, y, yaw, roll]), np.stack([seg.direction * v, roll])

    def command(self, est: Estimate, seg: ReferenceSegment, s0: float) -> Command:
        """Solve eq. 15 from ``est`` along ``seg`` (projection ``s0``); the first input is the command."""
        n, k_obs = self.p.horizon, self.p.n_obstacles
        xref, uref = self.reference(est, seg, s0)
        roll0 = float(np.clip(est.roll, -self.robot.max_roll_rad, self.robot.max_roll_rad))  # IMU noise
        x0 = np.array([est.x, est.y, est.yaw, roll0])
        pts = np.vstack([[est.x, est.y], xref[:2].T[:: max(1, n // 5)]])
        if self.obstacles is not None:
            obs = self.obstacles.nearby(pts, k_obs, within_m=self.robot.radius_m + 0.6)
        else:
            obs = np.zeros((k_obs, 3))
            obs[:, :2] = pts[0] + 1e2
        par = np.concatenate([x0, [est.v], xref.T.ravel(), uref.T.ravel(), obs.ravel()])
        lbx, ubx = self._lbx.copy(), self._ubx.copy()
        vsl = slice(self._nx, self._nx + self._nu, 2)
        if seg.direction > 0:
            lbx[vsl] = 0.0
        else:
            ubx[vsl] = 0.0
        if self._warm is not None:
            w0 = self._warm["x"]
            w0[:4] = x0
        else:
            w0 = np.concatenate([np.concatenate([x0, xref.T.ravel()]), uref.T.ravel(), np.zeros(n)])
        args: dict[str, Any] = {
            "x0": w0,
            "p": par,
            "lbx": lbx,
            "ubx": ubx,
            "lbg": self._lbg,
            "ubg": self._ubg,
        }
        if self._warm is not None:
            args["lam_x0"] = self._warm["lam_x"]
            args["lam_g0"] = self._warm["lam_g"]
        t0 = time.perf_counter()
        sol = self.solver(**args)
        ms = (time.perf_counter() - t0) * 1e3
        ok = bool(self.solver.stats()["success"])
        w = np.asarray(sol["x"]).ravel()
        if not ok or not np.all(np.isfinite(w)):
            self._warm = None
            return Command(0.0, est.roll, ok=False, solve_ms=ms)
        self._warm = {
            "x": w,
            "lam_x": np.asarray(sol["lam_x"]).ravel(),
            "lam_g": np.asarray(sol["lam_g"]).ravel(),
        }
        return Command(float(w[self._nx]), float(w[self._nx + 1]), ok=True, solve_ms=ms)


class PurePursuitTracker:
    """Geometric fallback: pure pursuit on the look-ahead point, speed from the stopping profile."""

    def __init__(
        self, robot: RobotProfile, lookahead_m: float = 0.5, cruise_m_s: float | None = None
    ) -> None:
        self.robot = robot
        self.lookahead_m = lookahead_m
        self.cruise = min(robot.max_speed_m_s, cruise_m_s or robot.max_speed_m_s)
        self.brake = 0.5 * robot.max_accel_m_s2

    def command(self, est: Estimate, seg: ReferenceSegment, s0: float) -> Command:
        tx, ty, _, troll = seg.sample(s0 + self.lookahead_m)
        dx, dy = float(tx) - est.x, float(ty) - est.y
        dist = math.hypot(dx, dy)
        heading = est.yaw if seg.direction > 0 else est.yaw + math.pi
        speed = float(speed_profile(seg, s0, self.cruise, self.brake))
        if (
            seg.length_m - s0 < 0.5
        ):  # near the end: also stop on passing the end line (loops end at the start)
            speed = min(speed, math.sqrt(2 * self.brake * max(seg.remaining(est.x, est.y), 0.0)))
        if dist < 0.05:
            return Command(seg.direction * speed, float(troll))
        alpha = wrap(math.atan2(dy, dx) - heading)
        kappa = 2.0 * math.sin(alpha) / dist
        roll = float(self.robot.roll_model.roll_for_curvature(seg.direction * kappa))
        roll = float(np.clip(roll, -self.robot.max_roll_rad, self.robot.max_roll_rad))
        return Command(seg.direction * speed, roll)
