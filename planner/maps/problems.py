"""Problem sets: JSON files of named start/goal problems on the shipped maps, for tests and the benchmark."""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from planner.errors import InvalidInput, NotFound
from planner.maps.catalogue import default_maps_dir


@dataclass(frozen=True)
class Problem:
    """One planning problem: poses are (x m, y m, yaw rad) in the map frame."""

    name: str
    map: str
    map_path: Path
    start: tuple[float, float, float]
    goal: tuple[float, float, float]
    solvable: bool
    time_limit_s: float

    def to_json(self) -> dict[str, Any]:
        return {
            "name": self.name,
            "map": self.map,
            "start": list(self.start),
            "goal": list(self.goal),
            "solvable": self.solvable,
            "time_limit_s": self.time_limit_s,
        }


def _pose(value: Any, field: str) -> tuple[float, float, float]:
    if (
        not isinstance(value, list)
        or len(value) != 3
        or not all(isinstance(v, int | float) and not isinstance(v, bool) for v in value)
        or not all(math.isfinite(v) for v in value)
    ):
        raise InvalidInput(field, f"must be three finite numbers [x, y, yaw], got {value!r}")
    return float(value[0]), float(value[1]), float(value[2])


def load_problem_set(path: str | Path) -> list[Problem]:
    """Read and validate a problem-set JSON: a list of {name, map, start, goal, solvable, time_limit_s}.

    ``map`` is a map file name resolved against the JSON's folder, then its parent (so
    ``maps/problems/garage.json`` may say ``"map": "garage.yaml"``). Errors name the field as
    ``problems[i].field``; names must be unique within the set.
    """
    p = Path(path)
    if not p.is_file():
        raise NotFound("problems", f"problem set {str(p)!r} does not exist")
    try:
        doc = json.loads(p.read_text())
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise InvalidInput("problems", f"{p.name} is not valid JSON: {exc}") from None
    if not isinstance(doc, list) or not doc:
        raise InvalidInput("problems", f"{p.name} must hold a non-empty JSON list of problems")
    problems: list[Problem] = []
    seen: set[str] = set()
    for i, item in enumerate(doc):
        where = f"problems[{i}]"
        if not isinstance(item, dict):
            raise InvalidInput(where, f"must be an object, got {type(item).__name__}")
        for key in ("name", "map", "start", "goal", "solvable", "time_limit_s"):
            if key not in item:
                raise InvalidInput(f"{where}.{key}", "required field missing")
        name, map_name = item["name"], item["map"]
        if not isinstance(name, str) or not name:
            raise InvalidInput(f"{where}.name", f"must be a non-empty string, got {name!r}")
        if name in seen:
            raise InvalidInput(f"{where}.name", f"duplicate problem name {name!r}")
        seen.add(name)
        if not isinstance(map_name, str) or not map_name:
            raise InvalidInput(f"{where}.map", f"must be a map file name, got {map_name!r}")
        candidates = [p.parent / map_name, p.parent.parent / map_name]
        map_path = next((c for c in candidates if c.is_file()), None)
        if map_path is None:
            raise NotFound(f"{where}.map", f"map {map_name!r} not found beside {p.name} nor one folder up")
        if not isinstance(item["solvable"], bool):
            raise InvalidInput(f"{where}.solvable", f"must be true or false, got {item['solvable']!r}")
        limit = item["time_limit_s"]
        number = isinstance(limit, int | float) and not isinstance(limit, bool)
        if not number or not (math.isfinite(limit) and limit > 0):
            raise InvalidInput(f"{where}.time_limit_s", f"must be a number > 0, got {limit!r}")
        problems.append(
            Problem(
                name=name,
                map=map_name,
                map_path=map_path,
                start=_pose(item["start"], f"{where}.start"),
                goal=_pose(item["goal"], f"{where}.goal"),
                solvable=item["solvable"],
                time_limit_s=float(limit),
            )
        )
    return problems


def list_problems(folder: str | Path | None = None) -> list[Problem]:
    """Every problem of every set in ``<folder>/problems/*.json`` (default :func:`default_maps_dir`)."""
    root = Path(folder) if folder is not None else default_maps_dir()
    sets = sorted((root / "problems").glob("*.json"))
    return [problem for path in sets for problem in load_problem_set(path)]
