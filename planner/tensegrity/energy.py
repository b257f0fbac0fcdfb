"""Direct physics check of TeXploR's statics: the potential energy of the two-arc body on a plane.

Independently of the paper's closed form, a rigid body resting on a horizontal plane with its up
direction ``u`` (unit vector in {b}) has its centre O_b at the height of its lowest point below O_b
(``lowest_depth``), so its potential energy is::

    U(u) = W g (depth(u) + u · c)            W total mass, c centre of mass in {b}

Stable static equilibria are the local minima of U over the sphere of up directions (the yaw about
z_s and the position on the plane do not change U). ``local_minimum`` descends from a given
orientation (Nelder–Mead in the tangent plane: U has kinks where the contact changes, so no
gradients); ``all_minima`` scans a latitude–longitude grid and refines every discrete minimum.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.optimize import minimize

from planner.tensegrity.geometry import G, TexplorParams, centre_of_mass, lowest_depth


def potential_energy(up_b: np.ndarray, theta1: float, theta2: float, params: TexplorParams) -> np.ndarray:
    """U(u) (J) for up vectors ``up_b`` (shape (..., 3), normalised here) and slider angles θ1, θ2 (rad)."""
    u = np.asarray(up_b, dtype=float)
    u = u / np.linalg.norm(u, axis=-1, keepdims=True)
    com = centre_of_mass(theta1, theta2, params)
    return np.asarray(params.total_mass_kg * G * (lowest_depth(u, params.radius_m) + u @ com))


def _tangent_basis(u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    helper = np.array([1.0, 0.0, 0.0]) if abs(u[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    e1 = np.cross(u, helper)
    e1 /= np.linalg.norm(e1)
    return e1, np.cross(u, e1)


def local_minimum(
    start_up_b: np.ndarray, theta1: float, theta2: float, params: TexplorParams, restarts: int = 3
) -> np.ndarray:
    """The local minimum of U (unit up vector in {b}) reached by descending from ``start_up_b``.

    Nelder–Mead on u = normalise(u0 + a e1 + b e2), restarted from its own result ``restarts`` times
    (the simplex can stall on U's kinks; a restart re-opens it).
    """
    u = np.asarray(start_up_b, dtype=float)
    u = u / np.linalg.norm(u)
    step = 0.02
    for _ in range(restarts):
        e1, e2 = _tangent_basis(u)
        base = u.copy()

        def energy(x: np.ndarray, base: np.ndarray = base, e1: np.ndarray = e1, e2: np.ndarray = e2) -> float:
            return float(potential_energy(base + x[0] * e1 + x[1] * e2, theta1, theta2, params))

        simplex = np.array([[0.0, 0.0], [step, 0.0], [0.0, step]])
        res = minimize(
            energy,
            np.zeros(2),
            method="Nelder-Mead",
            options={"initial_simplex": simplex, "xatol": 1e-11, "fatol": 1e-14, "maxiter": 4000},
        )
        u = base + res.x[0] * e1 + res.x[1] * e2
        u = u / np.linalg.norm(u)
        step *= 0.1
    return u


def all_minima(
    theta1: float, theta2: float, params: TexplorParams, n_lat: int = 90, n_lon: int = 180
) -> list[np.ndarray]:
    """Every local minimum of U (list of unit up vectors in {b}), from an ``n_lat × n_lon`` grid scan.

    A grid node lower than its 8 neighbours (longitude wraps) is refined with :func:`local_minimum`;
    results closer than 0.5° are merged.
    """
    lat = np.linspace(-math.pi / 2, math.pi / 2, n_lat + 2)[1:-1]
    lon = np.linspace(-math.pi, math.pi, n_lon, endpoint=False)
    la, lo = np.meshgrid(lat, lon, indexing="ij")
    grid = np.stack([np.cos(la) * np.cos(lo), np.cos(la) * np.sin(lo), np.sin(la)], axis=-1)
    energy = potential_energy(grid, theta1, theta2, params)
    padded = np.pad(energy, ((1, 1), (0, 0)), constant_values=np.inf)
    is_min = np.ones_like(energy, dtype=bool)
    for di in (-1, 0, 1):
        for dj in (-1, 0, 1):
            if di == 0 and dj == 0:
                continue
            neighbour = np.roll(padded, shift=(-di, -dj), axis=(0, 1))[1:-1]
            is_min &= energy <= neighbour
    found: list[np.ndarray] = []
    for i, j in zip(*np.nonzero(is_min), strict=True):
        u = local_minimum(grid[i, j], theta1, theta2, params)
        if all(float(np.degrees(np.arccos(np.clip(u @ v, -1.0, 1.0)))) > 0.5 for v in found):
            found.append(u)
    return found


def angle_deg(a: np.ndarray, b: np.ndarray) -> float:
    """Angle between two vectors in degrees."""
    cos = float(a @ b / (np.linalg.norm(a) * np.linalg.norm(b)))
    return math.degrees(math.acos(min(1.0, max(-1.0, cos))))
