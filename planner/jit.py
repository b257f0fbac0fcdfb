"""How the compiled kernels are compiled: :func:`njit_leaf` for the hot helpers that allocate nothing."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, TypeVar, cast

from numba import njit

F = TypeVar("F", bound=Callable[..., Any])

_NO_RUNTIME: dict[str, Any] = {"cache": True, "_nrt": False}


def njit_leaf(fn: F) -> F:
    """``@njit(cache=True)`` without numba's runtime (NRT): the function neither allocates nor reference-counts.

    A function compiled with the runtime increments the reference count of every array argument on entry and
    decrements it on every exit, each an atomic instruction. Inlined into the search loop, with seven arrays per
    footprint check and several checks per child, those were 7 % of a plan's CPU samples (issue 21, fifteenth
    round); a function that allocates nothing needs none of it. Its callees are compiled the same way, so they must
    not allocate either (numba refuses to compile it otherwise: "NRT required but not enabled").
    """
    return cast(F, njit(**_NO_RUNTIME)(fn))
