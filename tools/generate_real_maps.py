"""Generate the two synthetic Nav2-style maps of ``maps/real`` that do not come from Nav2: ``pockets`` and ``bays``.

Run from the repository root::

    python tools/generate_real_maps.py          # writes maps/real/pockets.{yaml,pgm} and bays.{yaml,pgm}

Both are deterministic (one seeded ``numpy.random.Generator`` each) and drawn on the grid directly, at Nav2's
usual 0.05 m:

* ``pockets`` (30 m × 20 m): a network of tube-like corridors 1.4–2.2 m wide, with dead-end side pockets
  0.9–1.6 m wide and 1.5–3.5 m deep off them — the kind of place where a sphere has to back out or turn in a
  pocket (the manoeuvre behind the multi-second tail on ``smoothers_world``).
* ``bays`` (24 m × 16 m): a hall with rows of parking bays on both sides (bay widths 1.0–1.6 m), pillars
  between them and a few scattered crates in the aisle.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from planner.maps.nav2 import save_map
from planner.occupancy import OccupancyGrid

REPO = Path(__file__).resolve().parent.parent
RES = 0.05


def _cells(m: float) -> int:
    return round(m / RES)


def _carve(free: np.ndarray, x0: float, y0: float, x1: float, y1: float) -> None:
    """Mark the rectangle [x0, x1] × [y0, y1] (m, origin at the lower left) free."""
    h = free.shape[0]
    r0, r1 = h - _cells(y1), h - _cells(y0)
    free[max(r0, 0):max(r1, 0), max(_cells(x0), 0):max(_cells(x1), 0)] = True


def make_pockets() -> OccupancyGrid:
    rng = np.random.default_rng(2101)
    w, h = 30.0, 20.0
    free = np.zeros((_cells(h), _cells(w)), bool)
    rows = [3.0, 10.0, 17.0]
    cols = [3.0, 11.0, 19.0, 27.0]
    for y in rows:  # horizontal tubes
        half = rng.uniform(0.7, 1.1)
        _carve(free, cols[0] - 1.0, y - half, cols[-1] + 1.0, y + half)
    for x in cols:  # vertical tubes
        half = rng.uniform(0.7, 1.1)
        _carve(free, x - half, rows[0] - 1.0, x + half, rows[-1] + 1.0)
    for _ in range(22):  # dead-end pockets off the tubes
        width, depth = rng.uniform(0.9, 1.6), rng.uniform(1.5, 3.5)
        if rng.random() < 0.5:
            y = float(rng.choice(rows))
            x = float(rng.uniform(cols[0] + 1.5, cols[-1] - 1.5))
            side = 1 if rng.random() < 0.5 else -1
            y_edge = y + side * 0.9
            _carve(free, x - width / 2, min(y_edge, y_edge + side * depth), x + width / 2,
                   max(y_edge, y_edge + side * depth))
        else:
            x = float(rng.choice(cols))
            y = float(rng.uniform(rows[0] + 1.5, rows[-1] - 1.5))
            side = 1 if rng.random() < 0.5 else -1
            x_edge = x + side * 0.9
            _carve(free, min(x_edge, x_edge + side * depth), y - width / 2, max(x_edge, x_edge + side * depth),
                   y + width / 2)
    return OccupancyGrid.from_occupied(~free, RES, name="pockets")


def make_bays() -> OccupancyGrid:
    rng = np.random.default_rng(2102)
    w, h = 24.0, 16.0
    free = np.zeros((_cells(h), _cells(w)), bool)
    _carve(free, 0.5, 5.5, 23.5, 10.5)  # the aisle, 5 m wide
    for top in (True, False):  # a row of bays on each side
        x = 1.0
        while x < 22.0:
            width = float(rng.uniform(1.0, 1.6))
            depth = float(rng.uniform(3.0, 4.5))
            if top:
                _carve(free, x, 10.5, x + width, 10.5 + depth)
            else:
                _carve(free, x, 5.5 - depth, x + width, 5.5)
            x += width + float(rng.uniform(0.3, 0.6))  # a pillar between bays
    for _ in range(5):  # crates in the aisle
        cx, cy = rng.uniform(3.0, 21.0), rng.uniform(6.5, 9.5)
        s = rng.uniform(0.3, 0.6)
        h_px = free.shape[0]
        free[h_px - _cells(cy + s):h_px - _cells(cy - s), _cells(cx - s):_cells(cx + s)] = False
    return OccupancyGrid.from_occupied(~free, RES, name="bays")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=REPO / "maps" / "real")
    args = parser.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    for grid in (make_pockets(), make_bays()):
        print(save_map(grid, args.out / f"{grid.name}.yaml"))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
