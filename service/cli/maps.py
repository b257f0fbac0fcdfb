"""``sphereplan maps``: list the shipped maps and problem sets, as a table (``--json``/``--out``: JSON).

The folder is ``--maps DIR``, else ``$SPHEREPLAN_MAPS``, else the repository's ``maps/`` folder next to the
``planner`` package (:func:`planner.maps.catalogue.default_maps_dir`).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

from planner.errors import NotFound
from service.cli._io import emit_json, say

VERB = "maps"
HELP = "list the shipped maps (grids and meshes) and problem sets (a table; --json for JSON)"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--maps", metavar="DIR", type=Path, default=None,
        help="maps folder (default: $SPHEREPLAN_MAPS, else the repository's maps/ folder)",
    )
    parser.add_argument("--json", action="store_true", help="print the JSON instead of the table")
    parser.add_argument("--out", metavar="FILE", help="write the JSON here (the table is not printed)")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from planner.maps.catalogue import default_maps_dir, list_maps
    from planner.maps.problems import list_problems

    folder = args.maps if args.maps is not None else default_maps_dir()
    if not folder.is_dir():
        raise NotFound("maps", f"{str(folder)!r} is not a directory")
    result = {
        "maps_dir": str(folder.resolve()),
        "maps": list_maps(folder),
        "problems": [
            {"map": p.map, "name": p.name, "solvable": p.solvable, "start": list(p.start),
             "goal": list(p.goal), "time_limit_s": p.time_limit_s}
            for p in list_problems(folder)
        ],
    }
    if args.json or args.out:
        emit_json(result, args.out)
    else:
        sys.stdout.write(format_table(result))
    say("maps", f"{len(result['maps'])} maps and {len(result['problems'])} problems in {result['maps_dir']}")
    return 0


def format_table(result: dict[str, Any]) -> str:
    """The maps (name, file, kind, size, resolution, problems on it) and the folder, for people."""
    per_map: dict[str, list[dict[str, Any]]] = {}
    for p in result["problems"]:
        per_map.setdefault(p["map"], []).append(p)
    rows = [("map", "file", "kind", "size (m)", "cell (m)", "problems (solvable/all)")]
    for m in result["maps"]:
        size = f"{m['size_m'][0]:g} × {m['size_m'][1]:g}" if "size_m" in m else m.get("error", "?")
        cell = "-" if m.get("resolution_m") is None else f"{m['resolution_m']:g}"
        kind = m["kind"] + (f" (from {m['mesh']})" if m.get("mesh") else "")
        probs = per_map.get(m["file"], [])
        count = f"{sum(p['solvable'] for p in probs)}/{len(probs)}" if probs else "-"
        rows.append((m["name"], m["file"], kind, size, cell, count))
    widths = [max(len(r[i]) for r in rows) for i in range(len(rows[0]))]
    lines = ["  ".join(cell.ljust(w) for cell, w in zip(row, widths, strict=True)).rstrip() for row in rows]
    return f"maps in {result['maps_dir']}\n" + "\n".join(lines) + "\n"
