"""Form finding of TeXploR's cable net (paper 002 §IV-A, eq. 17–18): the link pose T12 at rest.

Each link carries four cable anchors on its arc (link frame, radius r): the ends A (α = 0) and
B (α = π) and the middles C (α = 60°) and D (α = 120°). Twelve cables join link 1 to link 2 along the
paper's Euler path A1→C2→B1→D2→A1→B2→C1→A2→D1→B2→B1→A2→A1: every end meets all four anchors of the
other link, every middle meets the other link's two ends, so there are 4 edge-to-edge cables (free
length d_0,1 = 3.25 in) and 8 edge-to-middle cables (d_0,2 = 3 in), the paper's two classes.

Cable i has length |d_i| with d = P C1 − T12 P C2 (eq. 17) and energy ½ k_i (|d_i| − d_0,i)²
(tension only: a slack cable stores nothing). Eq. 18 minimises the sum over T12 ∈ SE(3), here
parametrised as R = exp(ω̂), o = v. Assumptions, not in the paper: printed eq. 17 puts the anchors at
0°, 60°, 240°, 180° (one off the arc) and labels the ends A, D; the labels above follow the Euler
path's degrees (ends have four cables) and keep every anchor on the semicircle.
"""

from __future__ import annotations

import itertools
import math
from typing import Any

import numpy as np

from planner.errors import InvalidInput
from planner.robot import RobotProfile
from planner.tensegrity.geometry import R12

INCH_M = 0.0254
#: Anchor arc angles (rad) in each link's frame.
ANCHORS = {"A": 0.0, "B": math.pi, "C": math.pi / 3, "D": 2 * math.pi / 3}
#: The Euler path of §IV-B; consecutive vertices are one cable (link-1 anchor, link-2 anchor).
EULER_PATH = ("A1", "C2", "B1", "D2", "A1", "B2", "C1", "A2", "D1", "B2", "B1", "A2", "A1")
#: The paper's reported optimum cable lengths (in): edge-to-edge d1, edge-to-middle d2.
PAPER_LENGTHS_IN = (5.8551, 5.5412)


def cables() -> list[tuple[str, str]]:
    """The 12 cables as (link-1 anchor, link-2 anchor), in Euler-path order."""
    out = []
    for u, v in itertools.pairwise(EULER_PATH):
        one, two = (u, v) if u.endswith("1") else (v, u)
        out.append((one[0], two[0]))
    return out


def _anchor(name: str, radius: float) -> np.ndarray:
    a = ANCHORS[name]
    return radius * np.array([math.cos(a), math.sin(a), 0.0])


def _pose(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    from scipy.spatial.transform import Rotation

    return Rotation.from_rotvec(x[:3]).as_matrix(), np.asarray(x[3:6])


def cable_lengths(rotation: np.ndarray, offset: np.ndarray, radius: float) -> np.ndarray:
    """|d_i| (m, shape (12,)) for link 2 at pose (rotation, offset) in link 1's frame (eq. 17)."""
    return np.array(
        [np.linalg.norm(_anchor(a, radius) - (rotation @ _anchor(b, radius) + offset)) for a, b in cables()]
    )


def _free_and_stiffness(edge_m: float, middle_m: float, stiffness: float) -> tuple[np.ndarray, np.ndarray]:
    free = np.array([edge_m if (a in "AB" and b in "AB") else middle_m for a, b in cables()])
    return free, np.full(12, stiffness)


def cable_energy(x: np.ndarray, radius: float, free: np.ndarray, stiffness: np.ndarray) -> float:
    """Eq. 18's objective (J) at pose parameters x = (ω, v) (rotation vector, offset in m)."""
    lengths = cable_lengths(*_pose(x), radius)
    stretch = np.maximum(lengths - free, 0.0)
    return float(0.5 * stiffness @ stretch**2)


def form_find(
    profile: RobotProfile, fix_centre: bool = False, starts: int = 16, seed: int = 0
) -> dict[str, Any]:
    """What ``sphereplan tensegrity formfind`` prints: the minimum-energy T12 and cable lengths.

    Runs BFGS from eq. 3's pose and ``starts`` − 1 seeded random poses; ``fix_centre`` keeps the arc
    centres coincident (o12 = 0, as eq. 3 assumes) and optimises the rotation only. Also reports how
    eq. 3's pose compares (energy, gradient) and the paper's lengths.
    """
    from scipy.optimize import minimize  # here, not at the top: `tensegrity static` never needs scipy
    from scipy.spatial.transform import Rotation

    if starts < 1:
        raise InvalidInput("starts", f"must be at least 1, got {starts}")
    section = profile.extra.get("texplor", {})
    radius = profile.radius_m
    stiffness_value = float(section.get("cable_stiffness_n_m", 200.0))
    free, stiffness = _free_and_stiffness(
        float(section.get("free_length_edge_m", 3.25 * INCH_M)),
        float(section.get("free_length_middle_m", 3.0 * INCH_M)),
        stiffness_value,
    )
    eq3 = np.concatenate([Rotation.from_matrix(R12).as_rotvec(), np.zeros(3)])
    mask = np.array([1, 1, 1, 0, 0, 0.0]) if fix_centre else np.ones(6)

    def energy(y: np.ndarray) -> float:
        return cable_energy(np.where(mask > 0, y, eq3), radius, free, stiffness)

    rng = np.random.default_rng(seed)
    best = None
    for k in range(starts):
        x0 = eq3.copy() if k == 0 else np.concatenate([rng.normal(0, 1.0, 3), rng.normal(0, radius / 3, 3)])
        res = minimize(energy, x0, method="BFGS", options={"gtol": 1e-10, "maxiter": 2000})
        if best is None or res.fun < best.fun - 1e-12:
            best = res
    assert best is not None
    x = np.where(mask > 0, best.x, eq3)
    rotation, offset = _pose(x)
    lengths = cable_lengths(rotation, offset, radius)
    t12 = np.eye(4)
    t12[:3, :3], t12[:3, 3] = rotation, offset
    rot_err = math.degrees(Rotation.from_matrix(rotation @ R12.T).magnitude())
    grad = np.array([(energy(eq3 + h) - energy(eq3 - h)) / 2e-7 for h in np.eye(6) * 1e-7])
    labels = [f"{a}1-{b}2" for a, b in cables()]
    edge = [i for i, (a, b) in enumerate(cables()) if a in "AB" and b in "AB"]
    middle = [i for i in range(12) if i not in edge]
    return {
        "robot": profile.name,
        "radius_m": radius,
        "fix_centre": fix_centre,
        "stiffness_n_m": stiffness_value,
        "free_length_m": {"edge_edge": float(free[edge[0]]), "edge_middle": float(free[middle[0]])},
        "energy_j": float(best.fun),
        "T12": t12.tolist(),
        "rotation_error_deg_vs_eq3": rot_err,
        "centre_offset_m": offset.tolist(),
        "cables": [
            {
                "cable": lab,
                "length_m": float(ln),
                "free_length_m": float(f),
                "tension_n": float(k * max(ln - f, 0.0)),
            }
            for lab, ln, f, k in zip(labels, lengths, free, stiffness, strict=True)
        ],
        "edge_edge_length_m": float(np.mean(lengths[edge])),
        "edge_middle_length_m": float(np.mean(lengths[middle])),
        "eq3_pose": {
            "energy_j": energy(eq3),
            "gradient_norm": float(np.linalg.norm(grad)),
            "cable_length_m": float(np.mean(cable_lengths(R12, np.zeros(3), radius))),
        },
        "paper": {
            "edge_edge_length_m": PAPER_LENGTHS_IN[0] * INCH_M,
            "edge_middle_length_m": PAPER_LENGTHS_IN[1] * INCH_M,
            "t12": "eq. 3 (orthogonal links, coincident centres)",
            **paper_fit(),
        },
    }


def paper_fit() -> dict[str, float]:
    """The (r, δ) that reproduce the paper's two lengths with eq. 3's rotation and centres δ apart along y.

    With coincident centres every cable has length r√2, so the paper's d1 ≠ d2 cannot come from eq. 3
    exactly. Offsetting link 2 by δ along y_b gives d1² = 2r² + δ², d2² = 2r² − √3 rδ + δ².
    """
    d1, d2 = (x * INCH_M for x in PAPER_LENGTHS_IN)
    product = (d1**2 - d2**2) / math.sqrt(3.0)  # r·δ
    # 2r² + (product / r)² = d1²  →  2 r⁴ − d1² r² + product² = 0, larger root.
    r_sq = (d1**2 + math.sqrt(d1**4 - 8.0 * product**2)) / 4.0
    radius = math.sqrt(r_sq)
    return {"fit_radius_m": radius, "fit_centre_offset_m": product / radius}
