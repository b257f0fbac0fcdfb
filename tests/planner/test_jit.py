"""The search's per-child helpers are compiled without numba's runtime (planner.jit.njit_leaf): no reference
counting of their array arguments, which was 7 % of a plan's CPU time when they had it."""

import numpy as np
import pytest

from planner.hybrid_astar import closed_set, heap, kernels
from planner.jit import njit_leaf
from planner.kinematics import arc_step, roll_shift, roll_shift_cs, wrap
from planner.maps import clearance

HOT = [heap.heap_push, heap.heap_pop, closed_set.contains, closed_set.add, kernels._closed_key, kernels._heuristic,
       kernels._travel, kernels._pose_margin_at, kernels._shift_margin_at, kernels._arc_margin_at,
       kernels._motion_margin, clearance.circle_margin_at, clearance.footprint_hits, wrap, roll_shift, roll_shift_cs,
       arc_step, clearance.convex_turn, clearance._square_meets_convex, clearance.circles_clear_at]


@pytest.mark.parametrize("fn", HOT, ids=lambda f: f.py_func.__name__)
def test_the_search_loops_helpers_run_without_reference_counting(fn) -> None:
    assert fn.targetoptions.get("_nrt") is False


def test_a_leaf_that_allocates_is_refused_and_one_that_does_not_runs() -> None:
    @njit_leaf
    def total(a: np.ndarray) -> float:
        s = 0.0
        for v in a:
            s += v
        return s

    @njit_leaf
    def doubled_sum(a: np.ndarray) -> float:
        return (a * 2.0).sum()  # allocates the doubled array

    assert total(np.arange(4.0)) == 6.0
    with pytest.raises(Exception, match="NRT required but not enabled"):
        doubled_sum(np.arange(4.0))
