"""Form finding (eq. 18): the cable graph, the optimum's shape, and the paper's numbers."""

from __future__ import annotations

import math
from collections import Counter

import numpy as np
import pytest

from planner.robot import load_robot
from planner.tensegrity import form_find
from planner.tensegrity.formfinding import INCH_M, PAPER_LENGTHS_IN, cables, paper_fit

PROFILE = load_robot("texplor")


def test_euler_path_gives_twelve_cables_in_two_classes() -> None:
    edges = cables()
    assert len(edges) == 12 and len(set(edges)) == 12
    degree = Counter([f"{a}1" for a, _ in edges] + [f"{b}2" for _, b in edges])
    assert degree == {"A1": 4, "B1": 4, "C1": 2, "D1": 2, "A2": 4, "B2": 4, "C2": 2, "D2": 2}
    classes = Counter("ee" if a in "AB" and b in "AB" else "em" for a, b in edges)
    assert classes == {"ee": 4, "em": 8}


def test_optimum_rotation_is_eq3() -> None:
    for fix in (True, False):
        result = form_find(PROFILE, fix_centre=fix, starts=4)
        assert result["rotation_error_deg_vs_eq3"] < 1e-3
        lengths = [c["length_m"] for c in result["cables"]]
        assert all(c["tension_n"] > 0 for c in result["cables"])
        if fix:
            # coincident centres: every cable spans r*sqrt(2), and eq. 3 is a critical point
            assert np.allclose(lengths, PROFILE.radius_m * math.sqrt(2))
            assert result["eq3_pose"]["gradient_norm"] < 1e-4
        else:
            assert result["energy_j"] < result["eq3_pose"]["energy_j"]
            assert result["edge_edge_length_m"] > result["edge_middle_length_m"]


def test_paper_lengths_fit_an_offset_eq3_pose() -> None:
    fit = paper_fit()
    r, d = fit["fit_radius_m"], fit["fit_centre_offset_m"]
    d1 = math.sqrt(2 * r**2 + d**2)
    d2 = math.sqrt(2 * r**2 - math.sqrt(3) * r * d + d**2)
    assert d1 == pytest.approx(PAPER_LENGTHS_IN[0] * INCH_M)
    assert d2 == pytest.approx(PAPER_LENGTHS_IN[1] * INCH_M)
