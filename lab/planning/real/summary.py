"""The real-map benchmark's per-map summaries, its table and its CSV."""

from __future__ import annotations

import csv
import logging
import math
import statistics
from collections.abc import Sequence
from dataclasses import asdict, dataclass, fields
from pathlib import Path
from typing import Any

import numpy as np

from lab.planning.real.runs import (
    BIT_DUBINS,
    BIT_REEDS_SHEPP,
    CSV_COLUMNS,
    REFERENCE_SPACES,
    ROOM_SPACES,
    SPHEREPLAN,
    RunRecord,
)
from lab.planning.referee import FootprintReferee

log = logging.getLogger(__name__)

Pose = tuple[float, float, float]


# ----------------------------------------------------------------------------------------------- summaries


@dataclass(frozen=True)
class MapSummary:
    """The per-map line of the table (times in s, lengths as ratios, clearances in m; nan where empty).

    ``bit_solved``: solved by BIT* on either space; ``ref_failed``: BIT* runs whose worker process crashed or that
    raised (status ``crashed`` / ``error``: reference failures, not solutions); ``missed``: solved by the reference
    for sphereplan's motions (Dubins, plus Reeds–Shepp when it may reverse) but not by sphereplan; ``refused_free``:
    starts or goals sphereplan called "in collision" although the padded polygon is free there (all drawn poses
    are); ``unsolved_*``: problems nobody solved and sphereplan did not refuse (``unsolved_time_p50_s``: how long
    sphereplan took to give up on them: timeout, no path or another planning error); ``disconnected_time_max_s``:
    the longest sphereplan took on a problem proven unreachable (its refusal time); ``time_*``: sphereplan on the
    problems it solved; ``both_*``: medians over the problems both sphereplan and the reference solved
    (``both_ratio_*``: sphereplan's time ÷ the faster reference's first-solution time, per problem, median and p90);
    ``length_ratio_*``: length ÷ the reference's best (final) length; ``first_ratio_median``: length ÷ the shortest
    BIT* first solution, ``longer_than_first``: the share of problems where sphereplan's path is longer than that;
    ``expansions_per_s``: sphereplan's expansions ÷ its time, summed over its solved problems;
    ``loop_expansions_per_s``: the same ÷ the time in its compiled search loop alone (the rate Nav2 reports);
    ``expansions_per_m``: sphereplan's expansions ÷ its path's length, median over its solved problems (issue 21's
    measure of how directly the search heads for the goal where there is room); ``clearance_*``:
    medians over sphereplan's solved problems of the path's least clearance, true (polygon) and as reported;
    ``shift_share_median``: sphereplan's sideways shifts (the roll changes', eq. 1) ÷ its path's length, median;
    ``rolled_ratio_median``: length ÷ the reference's best as a sphere would roll it (its length plus the shifts
    of its turns, :func:`~lab.planning.real.runs.rolled_shift_m`; the shortest such among the allowed spaces),
    median; ``rolled_first_ratio_median`` and ``longer_than_rolled_first``: ``first_ratio_median`` and
    ``longer_than_first`` with BIT*'s first solutions as a sphere would roll them (length plus ``first_shift_m``);
    ``room_runs``, ``room_solved``: runs and solutions of the room-matched reference (``--room-reference``: BIT* with
    the footprint grown by the room sphereplan's path keeps, on the problems sphereplan solved; not a solvability or
    length reference, and not counted in ``bit_*`` or ``missed``), ``room_ratio_*``: sphereplan's time ÷ its
    first-solution time, per problem where it solved, median and p90; ``backwards_share``: the metres sphereplan's
    paths roll backwards ÷ their length, summed over its solved problems that record it (what ``prefer_forward``
    buys).
    """

    map: str
    cells: str
    time_limit_s: float
    setup_s: float
    problems: int
    disconnected: int
    bit_dubins: int
    bit_reeds_shepp: int
    bit_solved: int
    ref_failed: int
    sphereplan: int
    missed: int
    refused_free: int
    timeouts: int
    bad_paths: int
    time_p50_s: float
    time_p90_s: float
    time_max_s: float
    both_sphereplan_p50_s: float
    both_bit_first_p50_s: float
    both_ratio_median: float
    both_ratio_p90: float
    unsolved: int
    unsolved_time_p50_s: float
    disconnected_time_max_s: float
    length_ratio_median: float
    length_ratio_max: float
    first_ratio_median: float
    longer_than_first: float
    expansions_per_s: float
    loop_expansions_per_s: float
    expansions_per_m: float
    clearance_median_m: float
    reported_clearance_median_m: float
    shift_share_median: float = math.nan
    rolled_ratio_median: float = math.nan
    rolled_first_ratio_median: float = math.nan
    longer_than_rolled_first: float = math.nan
    room_runs: int = 0
    room_solved: int = 0
    room_ratio_median: float = math.nan
    room_ratio_p90: float = math.nan
    backwards_share: float = math.nan


def _median(values: Sequence[float]) -> float:
    return float(statistics.median(values)) if values else math.nan


def _p90(values: Sequence[float]) -> float:
    return float(np.percentile(values, 90)) if values else math.nan


def summarise(records: Sequence[RunRecord], checkers: dict[str, FootprintReferee], reverse_allowed: bool,
              setup_s: dict[str, float], cells: dict[str, str]) -> list[MapSummary]:
    """One :class:`MapSummary` per map (in first-seen order), then one named ``all`` over every map."""
    spaces = {BIT_DUBINS, BIT_REEDS_SHEPP} if reverse_allowed else {BIT_DUBINS}
    maps = list(dict.fromkeys(r.map for r in records))
    out = [_summary(m, [r for r in records if r.map == m], checkers.get(m), spaces, setup_s.get(m, math.nan),
                    cells.get(m, "")) for m in maps]
    if len(maps) > 1:
        out.append(_summary("all", list(records), None, spaces, sum(setup_s.get(m, 0.0) for m in maps), "",
                            checkers))
    return out


def _summary(name: str, records: list[RunRecord], checker: FootprintReferee | None, spaces: set[str],
             setup_s: float, cells: str, checkers: dict[str, FootprintReferee] | None = None) -> MapSummary:
    by_problem: dict[tuple[str, int], dict[str, RunRecord]] = {}
    for r in records:
        by_problem.setdefault((r.map, r.problem), {})[r.planner] = r
    ours = [g[SPHEREPLAN] for g in by_problem.values() if SPHEREPLAN in g]
    solved = [r for r in ours if r.solved]

    def ref_solved(group: dict[str, RunRecord], allowed: set[str]) -> list[RunRecord]:
        return [group[p] for p in allowed if p in group and group[p].solved]

    refused_free = 0
    for r in ours:
        if r.status not in ("start_refused", "goal_refused"):
            continue
        check = checker or (checkers or {}).get(r.map)
        pose = (r.start_x, r.start_y, r.start_yaw) if r.status == "start_refused" else (r.goal_x, r.goal_y, r.goal_yaw)
        if check is None or not check.collides(*pose):
            refused_free += 1
    both_ours, both_bit, both_ratio, first_ratio, unsolved_times, rolled, rolled_first = [], [], [], [], [], [], []
    missed = 0
    for g in by_problem.values():
        mine = g.get(SPHEREPLAN)
        refs = ref_solved(g, spaces)
        if mine is not None and refs and not mine.solved:
            missed += 1
        if mine is not None and refs and mine.solved:
            both_ours.append(mine.time_s)
            both_bit.append(min(r.time_s for r in refs))
            both_ratio.append(mine.time_s / max(both_bit[-1], 1e-6))
            first_ratio.append(mine.length_m / min(r.first_length_m for r in refs))
            rolled_refs = [r.length_m + r.shift_m for r in refs if math.isfinite(r.shift_m)]
            if rolled_refs:  # (a CSV written before the shifts were recorded has none)
                rolled.append(mine.length_m / min(rolled_refs))
            rolled_firsts = [r.first_length_m + r.first_shift_m for r in refs if math.isfinite(r.first_shift_m)]
            if rolled_firsts:
                rolled_first.append(mine.length_m / min(rolled_firsts))
        anyone = (mine is not None and mine.solved) or bool(ref_solved(g, set(REFERENCE_SPACES)))
        if not anyone and mine is not None and mine.status in ("timeout", "no_path", "error"):
            unsolved_times.append(mine.time_s)
    room_runs = [g[p] for g in by_problem.values() for p in ROOM_SPACES if p in g]
    room_ratio = [g[SPHEREPLAN].time_s / max(g[p].time_s, 1e-6) for g in by_problem.values() for p in ROOM_SPACES
                  if p in g and g[p].solved and SPHEREPLAN in g and g[SPHEREPLAN].solved]
    ratios = [r.length_ratio for r in solved if math.isfinite(r.length_ratio)]
    limits = sorted({r.time_limit_s for r in records})
    return MapSummary(
        map=name, cells=cells, time_limit_s=limits[0] if len(limits) == 1 else math.nan, setup_s=setup_s,
        problems=len(by_problem), disconnected=sum(1 for g in by_problem.values()
                                                   if next(iter(g.values())).disconnected),
        bit_dubins=sum(1 for g in by_problem.values() if BIT_DUBINS in g and g[BIT_DUBINS].solved),
        bit_reeds_shepp=sum(1 for g in by_problem.values() if BIT_REEDS_SHEPP in g and g[BIT_REEDS_SHEPP].solved),
        bit_solved=sum(1 for g in by_problem.values() if ref_solved(g, set(REFERENCE_SPACES))),
        ref_failed=sum(1 for r in records if (r.planner in REFERENCE_SPACES or r.planner in ROOM_SPACES)
                       and r.status in ("crashed", "error")),
        sphereplan=len(solved), missed=missed, refused_free=refused_free,
        timeouts=sum(1 for r in ours if r.status == "timeout"),
        bad_paths=sum(1 for r in ours if r.status == "solved" and not r.valid),
        time_p50_s=_median([r.time_s for r in solved]), time_p90_s=_p90([r.time_s for r in solved]),
        time_max_s=max((r.time_s for r in solved), default=math.nan),
        both_sphereplan_p50_s=_median(both_ours), both_bit_first_p50_s=_median(both_bit),
        both_ratio_median=_median(both_ratio), both_ratio_p90=_p90(both_ratio),
        unsolved=len(unsolved_times), unsolved_time_p50_s=_median(unsolved_times),
        disconnected_time_max_s=max((r.time_s for r in ours if r.disconnected), default=math.nan),
        length_ratio_median=_median(ratios), length_ratio_max=max(ratios) if ratios else math.nan,
        first_ratio_median=_median(first_ratio),
        longer_than_first=_share_longer(first_ratio),
        expansions_per_s=(sum(r.expansions for r in solved if r.expansions > 0)
                          / max(sum(r.time_s for r in solved if r.expansions > 0), 1e-9)) if solved else math.nan,
        loop_expansions_per_s=_loop_rate(solved),
        expansions_per_m=_median([r.expansions / r.length_m for r in solved if r.expansions > 0 and r.length_m > 0]),
        clearance_median_m=_median([r.min_clearance_m for r in solved]),
        reported_clearance_median_m=_median([r.reported_clearance_m for r in solved]),
        shift_share_median=_median([r.shift_m / r.length_m for r in solved
                                    if math.isfinite(r.shift_m) and r.length_m > 0]),
        rolled_ratio_median=_median(rolled),
        rolled_first_ratio_median=_median(rolled_first), longer_than_rolled_first=_share_longer(rolled_first),
        room_runs=len(room_runs), room_solved=sum(1 for r in room_runs if r.solved),
        room_ratio_median=_median(room_ratio), room_ratio_p90=_p90(room_ratio),
        backwards_share=_share_backwards(solved),
    )


def _share_backwards(solved: Sequence[RunRecord]) -> float:
    """Metres rolled backwards ÷ length over the solved runs that record them (NaN when none does)."""
    known = [r for r in solved if math.isfinite(r.backwards_m) and r.length_m > 0]
    return sum(r.backwards_m for r in known) / sum(r.length_m for r in known) if known else math.nan


def _share_longer(ratios: Sequence[float]) -> float:
    """The share of length ratios above 1 (NaN when there are none)."""
    return sum(1 for v in ratios if v > 1.0 + 1e-9) / len(ratios) if ratios else math.nan


TABLE_COLUMNS = (
    ("map", "map"), ("cells", "cells"), ("limit s", "time limit given to each planner"),
    ("setup s", "preprocessing: sphereplan's planner for the map (distance field, cost and heuristic grids) and "
                "its reachability labels, once per map, not in the plan times"),
    ("n", "problems"), ("disc", "proven unreachable (disconnected)"),
    ("BIT*D", "solved by BIT* on Dubins"), ("BIT*RS", "solved by BIT* on Reeds–Shepp"),
    ("BIT*", "solved by BIT* (either)"), ("ref×", "BIT* runs that crashed or raised (reference failures)"),
    ("sp", "solved by sphereplan"),
    ("missed", "solved by the reference for sphereplan's motions, not by sphereplan"),
    ("refused", "free start/goal refused as in collision"), ("t/o", "sphereplan timeouts"),
    ("bad", "sphereplan paths the exact polygon check rejects"),
    ("p50 s", "sphereplan time p50, solved"), ("p90 s", "sphereplan time p90, solved"),
    ("max s", "sphereplan time max, solved"),
    ("both sp", "sphereplan p50 where both solved"), ("both BIT*", "BIT* first-solution p50 where both solved"),
    ("x med", "per problem: sphereplan time ÷ BIT* first-solution time, median (both solved)"),
    ("x p90", "the same ratio, p90"),
    ("unsolved", "problems nobody solved (sphereplan timed out or found none)"),
    ("give-up s", "sphereplan p50 time to give up on them"),
    ("disc s", "sphereplan's longest time on a proven-unreachable problem (refusal time)"),
    ("len med", "length ÷ reference best, median"), ("len max", "length ÷ reference best, max"),
    ("÷first", "length ÷ BIT*'s first solution, median"), (">first", "share longer than BIT*'s first solution"),
    ("exp/s", "sphereplan expansions per second of planning time (solved problems)"),
    ("loop exp/s", "the same per second in the compiled search loop alone (as Nav2 counts them)"),
    ("exp/m", "sphereplan expansions per metre of its path, median (solved problems)"),
    ("clear m", "sphereplan's true footprint clearance, median"),
    ("rep m", "sphereplan's reported min_clearance_m, median"),
    ("shift", "sphereplan's sideways shifts (roll changes) ÷ its length, median"),
    ("÷rolled", "length ÷ the reference's best plus the shifts a sphere pays to roll it, median"),
    ("÷1st rolled", "length ÷ BIT*'s first solution plus the shifts a sphere pays to roll it, median"),
    (">1st rolled", "share longer than BIT*'s first solution as a sphere would roll it"),
    ("back", "share of sphereplan's metres rolled backwards (all its solved paths)"),
)
# printed only when the room-matched reference ran (--room-reference)
ROOM_COLUMNS = (
    ("room", "solved by BIT* asked to keep the room sphereplan's path keeps (up to the preferred clearance), of its "
             "runs"),
    ("x room", "per problem: sphereplan time ÷ that BIT*'s first-solution time, median"),
    ("x room p90", "the same ratio, p90"),
)


def _loop_rate(solved: Sequence[RunRecord]) -> float:
    """Expansions per second of search-loop time over the solved runs that report it (NaN when none does)."""
    known = [r for r in solved if r.expansions > 0 and math.isfinite(r.search_loop_s) and r.search_loop_s > 0]
    if not known:
        return math.nan
    return sum(r.expansions for r in known) / sum(r.search_loop_s for r in known)


def _fmt(value: float, digits: int = 2) -> str:
    return "–" if not math.isfinite(value) else f"{value:.{digits}f}"


def format_real_table(summaries: Sequence[MapSummary]) -> str:
    """The per-map table (fixed-width text) with a legend of the columns."""
    rows = []
    room = any(s.room_runs > 0 for s in summaries)
    for s in summaries:
        rows.append([
            s.map, s.cells, _fmt(s.time_limit_s, 0), _fmt(s.setup_s, 3), str(s.problems), str(s.disconnected),
            str(s.bit_dubins), str(s.bit_reeds_shepp), str(s.bit_solved), str(s.ref_failed), str(s.sphereplan),
            str(s.missed),
            str(s.refused_free), str(s.timeouts), str(s.bad_paths), _fmt(s.time_p50_s, 3), _fmt(s.time_p90_s, 3),
            _fmt(s.time_max_s, 3), _fmt(s.both_sphereplan_p50_s, 3), _fmt(s.both_bit_first_p50_s, 3),
            _fmt(s.both_ratio_median, 2), _fmt(s.both_ratio_p90, 2), str(s.unsolved),
            _fmt(s.unsolved_time_p50_s, 3), _fmt(s.disconnected_time_max_s, 3), _fmt(s.length_ratio_median, 3),
            _fmt(s.length_ratio_max, 3),
            _fmt(s.first_ratio_median, 3), _fmt(s.longer_than_first, 2), _fmt(s.expansions_per_s, 0),
            _fmt(s.loop_expansions_per_s, 0), _fmt(s.expansions_per_m, 0),
            _fmt(s.clearance_median_m, 3), _fmt(s.reported_clearance_median_m, 3), _fmt(s.shift_share_median, 3),
            _fmt(s.rolled_ratio_median, 3), _fmt(s.rolled_first_ratio_median, 3),
            _fmt(s.longer_than_rolled_first, 2), _fmt(s.backwards_share, 2),
        ] + ([f"{s.room_solved}/{s.room_runs}", _fmt(s.room_ratio_median, 2), _fmt(s.room_ratio_p90, 2)]
             if room else []))
    columns = TABLE_COLUMNS + (ROOM_COLUMNS if room else ())
    head = [c[0] for c in columns]
    widths = [max(len(head[i]), *(len(r[i]) for r in rows)) for i in range(len(head))]
    line = "  ".join(h.ljust(widths[i]) if i < 2 else h.rjust(widths[i]) for i, h in enumerate(head))
    out = [line, "-" * len(line)]
    for r in rows:
        out.append("  ".join(v.ljust(widths[i]) if i < 2 else v.rjust(widths[i]) for i, v in enumerate(r)))
    out.append("")
    pad = max(len(short) for short, _ in columns)
    out.extend(f"  {short:{pad}s} {long}" for short, long in columns[2:])
    return "\n".join(out)


def write_real_csv(records: Sequence[RunRecord], path: str | Path) -> None:
    """One row per problem × planner, columns :data:`CSV_COLUMNS`."""
    with open(path, "w", newline="") as fh:
        writer = csv.DictWriter(fh, fieldnames=list(CSV_COLUMNS))
        writer.writeheader()
        for r in records:
            writer.writerow(asdict(r))


def read_real_csv(path: str | Path) -> list[RunRecord]:
    """The records of a CSV written by :func:`write_real_csv` (to re-plot or re-summarise a run)."""
    types = {f.name: f.type for f in fields(RunRecord)}
    out = []
    with open(path, newline="") as fh:
        for row in csv.DictReader(fh):
            values: dict[str, Any] = {}
            for key, text in row.items():
                kind = types[key]
                if kind == "bool":
                    values[key] = text == "True"
                elif kind == "int":
                    values[key] = int(text)
                elif kind == "float":
                    values[key] = float(text)
                else:
                    values[key] = text
            out.append(RunRecord(**values))
    return out


