"""The real-map benchmark's figure: time and length per problem and planner."""

from __future__ import annotations

import logging
import math
import textwrap
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from lab.planning.real.runs import (
    BIT_DUBINS,
    BIT_REEDS_SHEPP,
    BIT_ROOM_DUBINS,
    BIT_ROOM_REEDS_SHEPP,
    SHORT_NAMES,
    SPHEREPLAN,
    RunRecord,
)
from lab.planning.real.summary import MapSummary

log = logging.getLogger(__name__)

Pose = tuple[float, float, float]


def plot_real(records: Sequence[RunRecord], summaries: Sequence[MapSummary], path: str | Path, title: str) -> None:
    """A PNG summary: outcomes per map and planner, time per problem (failures drawn at the time limit),
    length ÷ reference, and the true footprint clearance of each path (style: :mod:`planner.plotstyle`)."""
    from planner.plotstyle import save

    save(real_figure(records, summaries, title), path, dpi=90)


def real_figure(records: Sequence[RunRecord], summaries: Sequence[MapSummary], title: str) -> Any:
    """The figure :func:`plot_real` writes: legends beside the panels, proved-unsolvable problems shaded and
    labelled, failures as × at the time they gave up."""
    from planner.plotstyle import legend_right, pyplot

    plt = pyplot()

    planners = [p for p in (SPHEREPLAN, BIT_DUBINS, BIT_REEDS_SHEPP, BIT_ROOM_DUBINS, BIT_ROOM_REEDS_SHEPP)
                if any(r.planner == p for r in records)]
    colours = {SPHEREPLAN: "tab:blue", BIT_DUBINS: "tab:orange", BIT_REEDS_SHEPP: "tab:green",
               BIT_ROOM_DUBINS: "tab:olive", BIT_ROOM_REEDS_SHEPP: "tab:cyan"}
    maps = list(dict.fromkeys(r.map for r in records))
    problems = list(dict.fromkeys((r.map, r.problem) for r in records))
    labels = [f"{m}#{i}" for m, i in problems]
    fig, axes = plt.subplots(4, 1, figsize=(max(10.0, 0.28 * len(problems) + 4), 15))
    fig.suptitle(textwrap.fill(title, 110), fontsize=10)

    ax = axes[0]  # outcomes
    outcomes = ("solved", "timeout", "no_path", "start_refused", "goal_refused", "error", "unsolved", "invalid")
    hatch_colours = {"solved": "tab:green", "timeout": "tab:red", "no_path": "tab:purple",
                     "start_refused": "tab:brown", "goal_refused": "tab:pink", "error": "black",
                     "unsolved": "tab:gray", "invalid": "gold"}
    width = 0.8 / len(planners)
    for k, planner in enumerate(planners):
        bottom = np.zeros(len(maps))
        for outcome in outcomes:
            counts = np.array([sum(1 for r in records if r.map == m and r.planner == planner and
                                   ("invalid" if r.status == "solved" and not r.valid else r.status) == outcome)
                               for m in maps], dtype=float)
            if not counts.any():
                continue
            ax.bar(np.arange(len(maps)) + k * width, counts, width, bottom=bottom, color=hatch_colours[outcome],
                   edgecolor=colours[planner], linewidth=1.5, label=outcome if k == 0 or outcome == "unsolved"
                   else None)
            bottom += counts
        for j in range(len(maps)):  # name each bar: sp, D (BIT* Dubins), RS (BIT* Reeds–Shepp)
            ax.text(j + k * width, bottom[j] + 0.1, SHORT_NAMES[planner], ha="center", va="bottom", fontsize=7)
    ax.set_xticks(np.arange(len(maps)) + 0.4 - width / 2)
    ax.set_xticklabels(maps, fontsize=8)
    per_map = max(sum(1 for r in records if r.map == m and r.planner == planners[0]) for m in maps)
    ax.set_ylim(0, per_map * 1.45)
    ax.set_ylabel("problems")
    room = any(p in (BIT_ROOM_DUBINS, BIT_ROOM_REEDS_SHEPP) for p in planners)
    ax.set_title("outcome per map and planner (sp = sphereplan, D = BIT* Dubins, RS = BIT* Reeds–Shepp"
                 + (", roomD / roomRS = BIT* keeping sphereplan's room, run where sphereplan solved)" if room else ")"))
    handles, names = ax.get_legend_handles_labels()
    unique = dict(zip(names, handles, strict=True))
    legend_right(ax, list(unique.values()))
    ax.get_legend().set_title("outcome", prop={"size": 7})

    x = np.arange(len(problems))
    lookup = {(r.map, r.problem, r.planner): r for r in records}
    unsolvable = {(r.map, r.problem) for r in records if r.disconnected}
    labels = [f"{lab} (unsolvable)" if key in unsolvable else lab for key, lab in zip(problems, labels, strict=True)]
    for a in axes[1:]:
        for i, key in enumerate(problems):
            if key in unsolvable:
                a.axvspan(i - 0.5, i + 0.5, color="0.9", zorder=0)
    ax = axes[1]  # times
    for k, planner in enumerate(planners):
        offs = (k - (len(planners) - 1) / 2) * 0.2
        ok = [(i, lookup[(m, p, planner)]) for i, (m, p) in enumerate(problems) if (m, p, planner) in lookup]
        good = [(i, r.time_s) for i, r in ok if r.solved]
        bad = [(i, r.time_s) for i, r in ok if not r.solved]
        if good:
            ax.plot([i + offs for i, _ in good], [t for _, t in good], "o", color=colours[planner],
                    label=f"{planner} (BIT*: first solution)" if planner != SPHEREPLAN else planner)
        if bad:
            ax.plot([i + offs for i, _ in bad], [max(t, 1e-3) for _, t in bad], "x", color=colours[planner], ms=9,
                    mew=2, label=f"{planner}: failed / unsolved")
    ax.set_yscale("log")
    ax.set_ylabel("time (s, log)")
    ax.set_title("time per problem (× = failed or unsolved, at the time it gave up; grey: proved unsolvable)")
    handles, _ = ax.get_legend_handles_labels()
    if unsolvable:
        from matplotlib.patches import Patch

        handles.append(Patch(fc="0.9", label="unsolvable (start and goal in different\nfree components)"))
    legend_right(ax, handles)

    ax = axes[2]  # length ratio
    ratios = [(i, lookup[(m, p, SPHEREPLAN)].length_ratio) for i, (m, p) in enumerate(problems)
              if (m, p, SPHEREPLAN) in lookup and math.isfinite(lookup[(m, p, SPHEREPLAN)].length_ratio)]
    if ratios:
        ax.bar([i for i, _ in ratios], [v for _, v in ratios], 0.6, color=colours[SPHEREPLAN])
        ax.set_ylim(min(0.9, min(v for _, v in ratios) - 0.05), max(1.3, max(v for _, v in ratios) + 0.05))
    ax.axhline(1.05, color="k", lw=0.8, ls="--", label="5 % longer than the reference")
    ax.axhline(1.0, color="k", lw=0.5)
    ax.set_ylabel("length ÷ BIT* reference")
    ax.set_title("sphereplan's length over the reference's final length (problems both solved; gaps: not both)")
    legend_right(ax)

    ax = axes[3]  # clearance
    for k, planner in enumerate(planners):
        offs = (k - (len(planners) - 1) / 2) * 0.2
        pts = [(i + offs, lookup[(m, p, planner)].min_clearance_m) for i, (m, p) in enumerate(problems)
               if (m, p, planner) in lookup and lookup[(m, p, planner)].solved]
        if pts:
            ax.plot([a for a, _ in pts], [b for _, b in pts], "o", color=colours[planner], label=planner)
    rep = [(i, lookup[(m, p, SPHEREPLAN)].reported_clearance_m) for i, (m, p) in enumerate(problems)
           if (m, p, SPHEREPLAN) in lookup and lookup[(m, p, SPHEREPLAN)].solved]
    if rep:
        ax.plot([a for a, _ in rep], [b for _, b in rep], "_", color="k", ms=10, label="sphereplan reported")
    ax.set_ylabel("least footprint clearance (m)")
    ax.set_title("true padded-footprint clearance along each solved path")
    legend_right(ax)
    for a in axes[1:]:
        a.set_xticks(x)
        a.set_xticklabels(labels, rotation=70, ha="right", fontsize=7)
        a.set_xlim(-0.7, len(problems) - 0.3)
        a.set_xlabel("problem (map#index)")
    fig.tight_layout(rect=(0, 0, 1, 0.97))
    return fig


