"""A binary min-heap on preallocated arrays, usable from numba-compiled code.

``keys`` (float64) and ``vals`` (int64) hold the entries; ``size[0]`` is the number in use. The caller
grows the arrays when ``size[0] == keys.size`` (``heap_push`` returns False then).
"""

from __future__ import annotations

import numpy as np

from planner.jit import njit_leaf


@njit_leaf
def heap_push(keys: np.ndarray, vals: np.ndarray, size: np.ndarray, key: float, val: int) -> bool:
    n = size[0]
    if n >= keys.size:
        return False
    i = n
    while i > 0:
        parent = (i - 1) >> 1
        if keys[parent] <= key:
            break
        keys[i] = keys[parent]
        vals[i] = vals[parent]
        i = parent
    keys[i] = key
    vals[i] = val
    size[0] = n + 1
    return True


@njit_leaf
def heap_pop(keys: np.ndarray, vals: np.ndarray, size: np.ndarray) -> tuple[float, int]:
    top_key = keys[0]
    top_val = vals[0]
    n = size[0] - 1
    size[0] = n
    if n == 0:
        return top_key, top_val
    key = keys[n]
    val = vals[n]
    i = 0
    while True:
        child = 2 * i + 1
        if child >= n:
            break
        if child + 1 < n and keys[child + 1] < keys[child]:
            child += 1
        if keys[child] >= key:
            break
        keys[i] = keys[child]
        vals[i] = vals[child]
        i = child
    keys[i] = key
    vals[i] = val
    return top_key, top_val
