"""The jobs the service runs in its worker processes, one function per capability.

Each job takes what its door validated, computes what the matching CLI verb prints and returns an
:class:`~service.outcome.Outcome`; it never raises, so nothing but outcomes crosses back from a worker.
A computation that meets an error is answered as the outcome table says (:mod:`service.outcome`).
"""

from __future__ import annotations

import logging
import math
import os
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from planner.errors import InvalidInput, PlanningError, SpherePlanError
from planner.occupancy import OccupancyGrid
from planner.robot import load_robot
from service.grids import inline_grid, load_map_file
from service.outcome import Outcome, error_outcome, ok_outcome, outcome_of_exception
from service.pipeline import execute_plan
from service.settings import MAX_TIME_LIMIT_S

log = logging.getLogger(__name__)


def worker_init() -> None:
    """Runs once in each worker process: import the planner (and its compiled code) up front."""
    logging.basicConfig(level=logging.WARNING, format="%(levelname)s worker %(process)d %(message)s")
    import planner.hybrid_astar.plan  # noqa: F401


def warm_up_job() -> int:
    """Plan once on a small synthetic map so that compiled code is loaded before the first request."""
    from planner.hybrid_astar.plan import plan_path

    occupied = np.zeros((50, 80), dtype=bool)
    occupied[[0, -1], :] = True
    occupied[:, [0, -1]] = True
    occupied[:15, 40] = True
    grid = OccupancyGrid.from_occupied(occupied, 0.1, name="warm-up")
    robot = load_robot(None)
    try:
        plan_path(grid, robot, (1.5, 1.0, 0.0), (6.5, 1.0, 0.0), time_limit_s=MAX_TIME_LIMIT_S)
    except PlanningError as exc:  # still warm: the compiled code ran
        log.warning("warm-up plan failed: %s", exc)
    return os.getpid()


def plan_job(request: dict[str, Any], map_path: str | None) -> Outcome:
    """Run one plan request (the JSON of a validated :class:`PlanRequest`) in a worker process.

    The same pipeline as ``sphereplan plan``: load the robot and the map, then
    :func:`service.pipeline.execute_plan`.
    """
    robot_json = None
    try:
        robot = load_robot(request.get("robot"))
        robot_json = robot.to_json()
        grid = load_map_file(Path(map_path), request.get("robot")) if map_path is not None else inline_grid(
            request["map"])
        result = execute_plan(request, grid, robot)
        return ok_outcome(result.to_json())
    except SpherePlanError as exc:
        return outcome_of_exception(exc, robot_json)
    except (ValueError, ArithmeticError) as exc:  # see _job
        log.warning("plan: computation failed for a request", exc_info=True)
        return error_outcome(InvalidInput, f"the plan computation failed for this input: {type(exc).__name__}: {exc}")
    except Exception as exc:  # a bug, not the client's fault: log it and answer 500
        log.exception("plan job failed")
        return outcome_of_exception(exc)


def simulate_job(request: dict[str, Any], map_path: str | None, robot_name: str) -> Outcome:
    """Run one simulate request in a worker: ``simulate_plan`` with the options of ``sphereplan simulate``."""
    from planner.closed_loop.simulate import SimulationOptions, simulate_plan
    from planner.closed_loop.tracker import MPCParams

    def compute() -> dict[str, Any]:
        grid = load_map_file(Path(map_path), None) if map_path is not None else inline_grid(request["map"])
        options = SimulationOptions(control_rate_hz=request["rate_hz"], tracker=request["tracker"],
                                    mpc=MPCParams(horizon=request["horizon"]), time_limit_s=request["time_limit_s"])
        return simulate_plan(grid, request["path"], load_robot(robot_name), seed=request["seed"],
                             noise=request["noise"], options=options)

    return _job("simulate", compute)


def _job(name: str, compute: Callable[[], Any]) -> Outcome:
    """Run one capability's computation: its JSON, or the error outcome.

    A ``ValueError``/``ArithmeticError`` that is not a sphereplan error means the request's numbers took
    the computation outside its domain (or produced NaN): answered as bad input (422), logged with the
    traceback so the unchecked case can be turned into a named error in ``planner/``.
    """
    try:
        return ok_outcome(compute())
    except SpherePlanError as exc:
        return outcome_of_exception(exc, plan=False)
    except (ValueError, ArithmeticError) as exc:
        log.warning("%s: computation failed for a request", name, exc_info=True)
        return error_outcome(InvalidInput, f"the {name} computation failed for this input: {type(exc).__name__}: {exc}")
    except Exception as exc:
        log.exception("%s job failed", name)
        return outcome_of_exception(exc)


def _radians(request: dict[str, Any], key: str) -> float:
    return math.radians(request[key]) if request["degrees"] else float(request[key])


def tensegrity_static_job(request: dict[str, Any]) -> Outcome:
    """``static_equilibria`` in a worker (what ``sphereplan tensegrity static`` prints)."""
    from planner.tensegrity import static_equilibria

    return _job("tensegrity", lambda: static_equilibria(
        _radians(request, "theta1"), _radians(request, "theta2"), load_robot(request["robot"]), request["verify"]))


def reconfigure_job(request: dict[str, Any], map_path: str | None) -> Outcome:
    """``plan_reconfiguration`` in a worker (what ``sphereplan reconfigure`` prints)."""
    from planner.spherobot.reconfigure import plan_reconfiguration

    def compute() -> dict[str, Any]:
        grid = None
        if map_path is not None:
            grid = load_map_file(Path(map_path), None)
        elif request["map"] is not None:
            grid = inline_grid(request["map"])
        return plan_reconfiguration({k: v for k, v in request.items() if k != "map"}, grid=grid)

    return _job("reconfigure", compute)


def vpip_rods_job(request: dict[str, Any]) -> Outcome:
    """``rods_report`` in a worker (what ``sphereplan vpip rods`` prints)."""
    from planner.vpip.api import rods_report

    return _job("vpip rods", lambda: rods_report(
        _radians(request, "phi_vpip"), _radians(request, "theta_vpip"), _radians(request, "roll"),
        _radians(request, "pitch_phase"), request["robot"]))


def vpip_schedule_job(request: dict[str, Any], robot_name: str) -> Outcome:
    """``schedule_report`` in a worker (the series ``sphereplan vpip schedule --out`` writes)."""
    from planner.vpip.api import schedule_report

    return _job("vpip schedule", lambda: schedule_report(request["path"], robot_name, request["driver"]))
