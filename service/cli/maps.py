"""``sphereplan maps``: list the shipped maps and problem sets as JSON.

The folder is ``--maps DIR``, else ``$SPHEREPLAN_MAPS``, else the repository's ``maps/`` folder next to the
``planner`` package (:func:`planner.maps.catalogue.default_maps_dir`).
"""

from __future__ import annotations

import argparse
from pathlib import Path

from planner.errors import NotFound
from service.cli._io import emit_json

VERB = "maps"
HELP = "list the shipped maps (grids and meshes) and problem sets as JSON"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--maps", metavar="DIR", type=Path, default=None,
        help="maps folder (default: $SPHEREPLAN_MAPS, else the repository's maps/ folder)",
    )
    parser.add_argument("--out", metavar="FILE", help="write the JSON here instead of stdout")
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
    emit_json(result, args.out)
    return 0
