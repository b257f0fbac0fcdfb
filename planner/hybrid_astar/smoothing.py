"""The smoother's passes, compiled: shortcutting a path of motions with rollable Dubins shots, forwards and
(mirrored) backwards, pass after pass until a pass gains less than a millimetre.

:meth:`planner.hybrid_astar.search.HybridAStar._smooth` describes what is done; this module does it in one compiled
call. Until issue 21's thirteenth round the passes, the direction runs and the mirroring ran in Python around
:func:`planner.hybrid_astar.kernels.shortcut`, converting the motions between lists and arrays a dozen times a plan:
about a millisecond a plan, a third of the smoothing time on the quick real-map problems. The shortcut kernel and
its decisions are unchanged (the paths are the same, bit for bit, on the real-map problems).

Motions are rows (held roll, curvature, signed arc length). A shortcut ends with a motion of length 0 that brings
the roll to the knot's: its curvature is the robot's at that roll, looked up in ``keys`` / ``curvs``
(:func:`curvature_table`; the roll model itself is Python).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np
from numba import njit

from planner.hybrid_astar.kernels import MAX_SHOT_SEGS, shortcut
from planner.jit import njit_leaf
from planner.kinematics import motion_knots, subdivide_rows


def curvature_table(motions: np.ndarray, rolls: Any, curvature: Callable[[np.ndarray], Any]
                    ) -> tuple[np.ndarray, np.ndarray]:
    """Every roll a knot of the smoothed path can hold (the motions' held rolls, mirrored, upright, and the rolls
    ``rolls`` a shot may turn with, both signs) and the robot's curvature there (``curvature``, the roll model's,
    called once on all of them), as two arrays."""
    held = np.asarray(motions, float).reshape(-1, 3)[:, 0]
    rolls = np.asarray(rolls, float).ravel()
    # (+ 0.0 makes a −0.0 key 0.0: np.unique keeps whichever of the equal zeros its sort puts first; with numpy 2.4.6
    # that was −0.0 on a zig-zag path, and the upright roll's curvature came out as −0.0)
    keys = np.unique(np.concatenate((held, -held, [0.0], rolls, -rolls))) + 0.0
    return keys, np.asarray(curvature(keys), dtype=float).reshape(keys.shape)


@njit_leaf
def _curvature_at(roll: float, keys: np.ndarray, curvs: np.ndarray) -> float:
    """The curvature at ``roll`` from :func:`curvature_table`'s arrays (an error when the roll is not there)."""
    for k in range(keys.size):
        if keys[k] == roll:
            return curvs[k]
    raise ValueError("smoothing: a knot's roll is missing from the curvature table")


@njit(cache=True)
def path_length(x: float, y: float, yaw: float, motions: np.ndarray, radius: float) -> float:
    """Distance the centre travels along the motions from (x, y, yaw) upright (arcs and roll changes' shifts)."""
    return motion_knots(x, y, yaw, 0.0, motions, radius)[-1, 4]


@njit_leaf
def cusps(motions: np.ndarray) -> int:
    """Changes of travel direction along the motions (a motion of length 0 keeps the direction before it)."""
    n = 0
    last = 0
    for k in range(motions.shape[0]):
        s = motions[k, 2]
        d = 1 if s > 0 else -1 if s < 0 else 0
        if d != 0 and last != 0 and d != last:
            n += 1
        if d != 0:
            last = d
    return n


@njit(cache=True)
def _run(clear: np.ndarray, blocked: np.ndarray, p: np.ndarray, offx: np.ndarray, offy: np.ndarray, px: np.ndarray,
         py: np.ndarray, x: float, y: float, yaw: float, roll: float, motions: np.ndarray, max_tries: int,
         recheck: int, counts: np.ndarray, radius: float, keys: np.ndarray, curvs: np.ndarray) -> np.ndarray:
    """The motions from (x, y, yaw) at ``roll`` with runs replaced by shorter, collision-free rollable Dubins shots
    (:func:`planner.hybrid_astar.kernels.shortcut`), each followed by a motion of length 0 to its knot's roll."""
    knots = motion_knots(x, y, yaw, roll, motions, radius)
    n = knots.shape[0]
    out_ij = np.zeros((n, 2), dtype=np.int64)
    out_roll = np.zeros((n, MAX_SHOT_SEGS))
    out_curv = np.zeros((n, MAX_SHOT_SEGS))
    out_len = np.zeros((n, MAX_SHOT_SEGS))
    out_n = np.zeros(n, dtype=np.int64)
    count = shortcut(clear, blocked, p, offx, offy, px, py, knots[:, :4].copy(), knots[:, 4].copy(), max_tries,
                     recheck, out_ij, out_roll, out_curv, out_len, out_n, counts)
    if count == 0:
        return motions
    rows = motions.shape[0]
    for c in range(count):
        rows += out_n[c] + 1
    out = np.empty((rows, 3))
    w = 0
    k = 0
    for c in range(count):
        i, j = out_ij[c, 0], out_ij[c, 1]
        for m in range(k, i):
            out[w] = motions[m]
            w += 1
        for m in range(out_n[c]):
            out[w, 0], out[w, 1], out[w, 2] = out_roll[c, m], out_curv[c, m], out_len[c, m]
            w += 1
        end_roll = knots[j, 3]
        out[w, 0], out[w, 1], out[w, 2] = end_roll, _curvature_at(end_roll, keys, curvs), 0.0
        w += 1
        k = j
    for m in range(k, motions.shape[0]):
        out[w] = motions[m]
        w += 1
    return out[:w]


@njit(cache=True)
def turned_round(offx: np.ndarray, offy: np.ndarray, px: np.ndarray, py: np.ndarray
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The footprint's covering-circle offsets and polygon turned by π (for a pose whose heading was turned by π:
    a mirrored reverse stretch)."""
    return -offx, -offy, -px, -py


@njit(cache=True)
def _run_backwards(clear: np.ndarray, blocked: np.ndarray, p: np.ndarray, offx: np.ndarray, offy: np.ndarray,
                   px: np.ndarray, py: np.ndarray, x: float, y: float, yaw: float, roll: float, motions: np.ndarray,
                   max_tries: int, recheck: int, counts: np.ndarray, radius: float, keys: np.ndarray,
                   curvs: np.ndarray) -> np.ndarray:
    """:func:`_run` with reverse shots: the motions are shortcut as the forward ones they mirror. With the heading
    turned by π the sphere rolls them forwards with every roll and curvature negated (eq. 1 is unchanged under
    (yaw, φ, κ, s) → (yaw + π, −φ, −κ, −s)) and the footprint (``offx`` … ``py`` as given, unturned) turned by π."""
    tx, ty, tpx, tpy = turned_round(offx, offy, px, py)
    done = _run(clear, blocked, p, tx, ty, tpx, tpy, x, y, yaw + math.pi, -roll, -motions, max_tries, recheck, counts,
                radius, keys, curvs)
    return -done + 0.0  # + 0.0: no negative zeros


@njit(cache=True)
def shortcut_path(clear: np.ndarray, blocked: np.ndarray, p: np.ndarray, offx: np.ndarray, offy: np.ndarray,
                  px: np.ndarray, py: np.ndarray, x: float, y: float, yaw: float, motions: np.ndarray, max_tries: int,
                  recheck: int, counts: np.ndarray, radius: float, keys: np.ndarray, curvs: np.ndarray
                  ) -> np.ndarray:
    """One pass: the whole path with forward shots (which may also replace a manoeuvre with cusps); then, when it
    still has cusps and rolls backwards somewhere, the whole path with reverse shots (a shorter one may replace a
    manoeuvre in a path that rolls backwards, which the forward shots cannot: the sphere faces the other way); then
    each stretch travelled backwards with reverse shots. The cusps left stay where they are."""
    motions = _run(clear, blocked, p, offx, offy, px, py, x, y, yaw, 0.0, motions, max_tries, recheck, counts, radius,
                   keys, curvs)
    backwards = False
    for k in range(motions.shape[0]):
        if motions[k, 2] < 0:
            backwards = True
    if not backwards:
        return motions
    if cusps(motions) > 0:
        motions = _run_backwards(clear, blocked, p, offx, offy, px, py, x, y, yaw, 0.0, motions, max_tries, recheck,
                                 counts, radius, keys, curvs)
    # the stretches of one direction (a motion of length 0 joins the stretch it is in; one at the start rolls
    # forwards), each stretch backwards shortcut from where the path (as it was) reaches it
    parts = []
    roll = 0.0
    a = 0
    n = motions.shape[0]
    while a < n:
        s = motions[a, 2]
        direction = -1 if s < 0 else 1
        b = a + 1
        while b < n and not (motions[b, 2] != 0 and (1 if motions[b, 2] > 0 else -1) != direction):
            b += 1
        stretch = motions[a:b]
        if direction > 0:
            parts.append(stretch)
        else:
            parts.append(_run_backwards(clear, blocked, p, offx, offy, px, py, x, y, yaw, roll, stretch, max_tries,
                                        recheck, counts, radius, keys, curvs))
        end = motion_knots(x, y, yaw, roll, stretch, radius)[-1]
        x, y, yaw, roll = end[0], end[1], end[2], end[3]
        a = b
    rows = 0
    for part in parts:
        rows += part.shape[0]
    out = np.empty((rows, 3))
    w = 0
    for part in parts:
        out[w:w + part.shape[0]] = part
        w += part.shape[0]
    return out


@njit(cache=True)
def smooth_path(clear: np.ndarray, blocked: np.ndarray, p: np.ndarray, offx: np.ndarray, offy: np.ndarray,
                px: np.ndarray, py: np.ndarray, x: float, y: float, yaw: float, motions: np.ndarray, passes: int,
                first_tries: int, later_tries: int, first_recheck: int, later_recheck: int, step: float,
                counts: np.ndarray, radius: float, keys: np.ndarray, curvs: np.ndarray) -> np.ndarray:
    """Shortcut passes (:func:`shortcut_path`) while they shorten the path by more than a millimetre: the first on
    the motions as given, with ``first_tries`` targets a knot and ``first_recheck``; the later ones on the path
    subdivided to ``step``, with ``later_tries`` and ``later_recheck``."""
    length = path_length(x, y, yaw, motions, radius)
    for k in range(passes):
        later = k > 0
        candidate = shortcut_path(clear, blocked, p, offx, offy, px, py, x, y, yaw,
                                  subdivide_rows(motions, step) if later else motions,
                                  later_tries if later else first_tries, later_recheck if later else first_recheck,
                                  counts, radius, keys, curvs)
        new_length = path_length(x, y, yaw, candidate, radius)
        if new_length > length - 1e-3:
            break
        motions, length = candidate, new_length
    return motions

