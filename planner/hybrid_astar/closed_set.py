"""The search's closed set of (cell, yaw bin, roll bin) keys, numbered as
:func:`planner.hybrid_astar.kernels._closed_key` does: a dense bitset on small maps, a hash set on large ones.

A dense bitset holds one bit for every key of the map: width × height × yaw bins × roll bins bits per search. On a
small map that is a few megabytes whose neighbouring keys share cache lines, the fastest set there is. On a
4-million-cell map it is 108 MB at the default bins, whose pages are zeroed as the search first touches them (the
searches there ran at a quarter of the small maps' expansions per second), and it capped the map size. Above
DENSE_MAX_MB the search uses a hash set instead (open addressing, linear probing, Fibonacci hashing), sized by the
search, not the map: a search closes at most one key per expansion, so a table of twice the node storage's capacity
(:class:`planner.hybrid_astar.search._Search` grows both together) is never more than half full.

A search holds both arrays; the one not in use is empty (``bits``) or of one slot (``table``). A hash ``table``
holds the keys, EMPTY (the least int64, which no key reaches) where empty; its size is a power of two.

Zeroing a bitset of several megabytes took 0.25–0.35 ms (11.7 MB on depot), a sixth of a short plan's time there
(issue 21, fifteenth round): a planner keeps the bitsets of its finished searches in a :class:`BitsetPool`, each cleared
where its search closed keys (:func:`planner.hybrid_astar.kernels.clear_closed`), and a new search takes one.
"""

from __future__ import annotations

import threading

import numpy as np
from numba import njit

from planner.jit import njit_leaf

DENSE_MAX_MB = 16.0  # maps whose bitset would exceed this use the hash set (measured: docs/planning.md)
EMPTY = -(2**63)
_MUL = -7046029254386353131  # 0x9E3779B97F4A7C15 (2^64 / golden ratio) as int64: Fibonacci hashing
_SHIFT = 29  # the product's bits from here up index the table (the low bits of a product mix poorly)


def dense_bytes(n_keys: int) -> int:
    return n_keys // 8 + 1


def uses_bitset(n_keys: int) -> bool:
    """Whether a map with ``n_keys`` closed-set keys gets a dense bitset (else the hash set)."""
    return dense_bytes(n_keys) <= DENSE_MAX_MB * 2**20


def new_sets(n_keys: int, capacity: int, pool: BitsetPool | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(bits, table) for a search on a map of ``n_keys`` keys whose node storage holds ``capacity`` nodes; a
    bitset from ``pool`` when it has one (all zero, as a new one)."""
    if uses_bitset(n_keys):
        bits = pool.take() if pool is not None else None
        if bits is None or bits.size != dense_bytes(n_keys):
            bits = np.zeros(dense_bytes(n_keys), dtype=np.uint8)
        return bits, np.full(1, EMPTY, dtype=np.int64)
    return np.zeros(0, dtype=np.uint8), new_table(capacity)


class BitsetPool:
    """Cleared bitsets of finished searches, for the next searches on the same map (thread-safe).

    At most ``keep`` are kept (a plan runs up to two searches at once: the start's and the goal side's or the
    forward alternative); a search whose bitset is not given back leaves it to the garbage collector as before.
    """

    def __init__(self, keep: int = 2) -> None:
        self.keep = keep
        self._free: list[np.ndarray] = []
        self._lock = threading.Lock()

    def take(self) -> np.ndarray | None:
        """A bitset that is all zero, or None when there is none."""
        with self._lock:
            return self._free.pop() if self._free else None

    def give_back(self, bits: np.ndarray) -> None:
        """Keep ``bits``, which the caller has cleared, for a later search (unless ``keep`` are kept already)."""
        with self._lock:
            if len(self._free) < self.keep:
                self._free.append(bits)

    def __len__(self) -> int:
        return len(self._free)


def new_table(capacity: int) -> np.ndarray:
    """An empty hash table for at least ``capacity`` keys at a load of at most one half."""
    size = 1
    while size < 2 * capacity:
        size <<= 1
    return np.full(size, EMPTY, dtype=np.int64)


@njit(cache=True, inline="always")
def _slot(table: np.ndarray, key: int) -> int:
    mask = table.size - 1
    i = ((key * _MUL) >> _SHIFT) & mask
    while table[i] != EMPTY and table[i] != key:
        i = (i + 1) & mask
    return i


@njit_leaf
def contains(table: np.ndarray, key: int) -> bool:
    return table[_slot(table, key)] == key


@njit_leaf
def add(table: np.ndarray, key: int) -> None:
    """Add ``key`` to the hash table (the caller keeps the load at most one half)."""
    table[_slot(table, key)] = key


@njit(cache=True, inline="always")
def is_closed(bits: np.ndarray, table: np.ndarray, key: int) -> bool:
    if bits.size > 0:
        return (bits[key >> 3] & (1 << (key & 7))) != 0
    return contains(table, key)


@njit(cache=True, inline="always")
def close(bits: np.ndarray, table: np.ndarray, key: int) -> None:
    if bits.size > 0:
        bits[key >> 3] |= 1 << (key & 7)
    else:
        add(table, key)


@njit(cache=True)
def rehash(table: np.ndarray, out: np.ndarray) -> None:
    """Put every key of ``table`` into the empty (larger) ``out``."""
    for k in table:
        if k != EMPTY:
            out[_slot(out, k)] = k
