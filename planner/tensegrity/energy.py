"""Direct physics check of TeXploR's statics: the potential energy of the two-arc body on a plane.

Independently of the paper's closed form, a rigid body resting on a horizontal plane with its up
direction ``u`` (unit vector in {b}) has its centre O_b at the height of its lowest point below O_b
(``lowest_depth``), so its potential energy is::

    U(u) = W g (depth(u) + u · c)            W total mass, c centre of mass in {b}

Stable static equilibria are the local minima of U over the sphere of up directions (the yaw about
z_s and the position on the plane do not change U). ``local_minimum`` descends from a given
orientation (Nelder–Mead in the tangent plane, in plain floats: U has kinks where the contact changes, so no
gradients); ``all_minima`` scans a latitude–longitude grid and refines every discrete minimum.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

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


def _scalar_energy(theta1: float, theta2: float, params: TexplorParams) -> Callable[[float, float, float], float]:
    """U(u) for one (unnormalised) up vector, in plain floats: :func:`potential_energy` without numpy.

    The descent below evaluates U tens of thousands of times on single vectors, where numpy's per-call
    overhead (~20 µs) is the whole cost; this is the same formula (``lowest_depth`` inlined) at ~1 µs.
    """
    cx, cy, cz = (float(v) for v in centre_of_mass(theta1, theta2, params))
    r = params.radius_m
    weight = params.total_mass_kg * G
    sqrt, hypot = math.sqrt, math.hypot

    def energy(ux: float, uy: float, uz: float) -> float:
        norm = sqrt(ux * ux + uy * uy + uz * uz)
        ux, uy, uz = ux / norm, uy / norm, uz / norm
        wx, wy, wz = -ux, -uy, -uz
        h1 = hypot(wx, wy) if wy >= 0.0 else abs(wx)
        h2 = hypot(wz, wy) if -wy >= 0.0 else abs(wz)
        return weight * (r * max(h1, h2) + (ux * cx + uy * cy + uz * cz))

    return energy


def _nelder_mead_2d(
    f: Callable[[float, float], float], step: float, xatol: float, fatol: float, maxiter: int
) -> tuple[float, float]:
    """Minimise f(a, b) from (0, 0) with the simplex (0,0), (step,0), (0,step); returns the best point.

    The textbook Nelder–Mead of :func:`scipy.optimize.minimize` (``method="Nelder-Mead"``, not adaptive,
    reflection 1, expansion 2, contraction ½, shrink ½, the same stopping test and stable ordering),
    written for two variables in plain floats: scipy's version spends ~25 µs of array overhead per step.
    """
    sim = [(0.0, 0.0), (step, 0.0), (0.0, step)]
    fs = [f(*p) for p in sim]
    order = sorted(range(3), key=fs.__getitem__)
    sim, fs = [sim[i] for i in order], [fs[i] for i in order]
    iterations = 1
    while iterations < maxiter:
        (x0, y0), (x1, y1), (x2, y2) = sim
        if (
            max(abs(x1 - x0), abs(y1 - y0), abs(x2 - x0), abs(y2 - y0)) <= xatol
            and max(abs(fs[0] - fs[1]), abs(fs[0] - fs[2])) <= fatol
        ):
            break
        xb, yb = (x0 + x1) / 2, (y0 + y1) / 2
        xr, yr = 2 * xb - x2, 2 * yb - y2
        fr = f(xr, yr)
        shrink = False
        if fr < fs[0]:
            xe, ye = 3 * xb - 2 * x2, 3 * yb - 2 * y2
            fe = f(xe, ye)
            sim[2], fs[2] = ((xe, ye), fe) if fe < fr else ((xr, yr), fr)
        elif fr < fs[1]:
            sim[2], fs[2] = (xr, yr), fr
        elif fr < fs[2]:
            xc, yc = 1.5 * xb - 0.5 * x2, 1.5 * yb - 0.5 * y2
            fc = f(xc, yc)
            if fc <= fr:
                sim[2], fs[2] = (xc, yc), fc
            else:
                shrink = True
        else:
            xcc, ycc = 0.5 * xb + 0.5 * x2, 0.5 * yb + 0.5 * y2
            fcc = f(xcc, ycc)
            if fcc < fs[2]:
                sim[2], fs[2] = (xcc, ycc), fcc
            else:
                shrink = True
        if shrink:
            for j in (1, 2):
                xj, yj = sim[j]
                sim[j] = (x0 + 0.5 * (xj - x0), y0 + 0.5 * (yj - y0))
                fs[j] = f(*sim[j])
        iterations += 1
        order = sorted(range(3), key=fs.__getitem__)
        sim, fs = [sim[i] for i in order], [fs[i] for i in order]
    return sim[0]


def _in_tangent_plane(
    energy: Callable[[float, float, float], float], u: np.ndarray, e1: np.ndarray, e2: np.ndarray
) -> Callable[[float, float], float]:
    """(a, b) ↦ U(u + a e1 + b e2)."""
    bx, by, bz = (float(v) for v in u)
    ax, ay, az = (float(v) for v in e1)
    cx, cy, cz = (float(v) for v in e2)

    def along(a: float, b: float) -> float:
        return energy(bx + a * ax + b * cx, by + a * ay + b * cy, bz + a * az + b * cz)

    return along


def local_minimum(
    start_up_b: np.ndarray, theta1: float, theta2: float, params: TexplorParams, restarts: int = 3
) -> np.ndarray:
    """The local minimum of U (unit up vector in {b}) reached by descending from ``start_up_b``.

    Nelder–Mead on u = normalise(u0 + a e1 + b e2), restarted from its own result ``restarts`` times
    (the simplex can stall on U's kinks; a restart re-opens it).
    """
    u = np.asarray(start_up_b, dtype=float)
    u = u / np.linalg.norm(u)
    energy = _scalar_energy(theta1, theta2, params)
    step = 0.02
    for _ in range(restarts):
        e1, e2 = _tangent_basis(u)
        along = _in_tangent_plane(energy, u, e1, e2)
        a, b = _nelder_mead_2d(along, step, xatol=1e-11, fatol=1e-14, maxiter=4000)
        u = u + a * e1 + b * e2
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
