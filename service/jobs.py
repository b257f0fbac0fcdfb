"""The jobs the service runs in its worker processes, one function per capability.

Each job takes what its door validated, computes what the matching CLI verb prints and returns an
:class:`~service.outcome.Outcome`; it never raises, so nothing but outcomes crosses back from a worker.
A computation that meets an error is answered as the outcome table says (:mod:`service.outcome`).
"""

from __future__ import annotations

import logging
import os
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from planner.errors import InvalidInput, PlanningError, SpherePlanError
from planner.occupancy import OccupancyGrid
from planner.robot import RobotProfile, load_robot
from planner.termination import Termination
from service.grids import load_grid
from service.outcome import UNKNOWN_ERROR_CODE, Outcome, answer_for, error_outcome, ok_outcome, outcome_of_exception
from service.pipeline import PlanQuery, execute_plan
from service.settings import MAX_TIME_LIMIT_S

#: the names a ``/v1/perceive`` request's parts are reported by
PERCEIVE_FIELDS = ("left_image", "right_image", "left_info", "right_info")

if TYPE_CHECKING:
    from planner.closed_loop.simulate import SimulationOptions
    from planner.spherobot.request import ReconfigureRequest
    from service.wire import InlineGrid

log = logging.getLogger(__name__)

#: the worker's cancel flag (a shared byte the supervising pool sets), when running in a SupervisedPool
_CANCEL_FLAG: Any = None


def set_cancel_flag(flag: Any) -> None:
    """Called once in each worker process by :mod:`service.pool` with the flag it sets to cancel a job."""
    global _CANCEL_FLAG
    _CANCEL_FLAG = flag


def cancelled() -> bool:
    """True once the pool asked this worker to stop its job (the planner polls it between search chunks)."""
    return _CANCEL_FLAG is not None and bool(_CANCEL_FLAG.value)


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
        plan_path(grid, robot, (1.5, 1.0, 0.0), (6.5, 1.0, 0.0), termination=Termination(MAX_TIME_LIMIT_S))
    except PlanningError as exc:  # still warm: the compiled code ran
        log.warning("warm-up plan failed: %s", exc)
    return os.getpid()


def _job(name: str, compute: Callable[[], Any], plan_robot: Callable[[], Any] | None = None) -> Outcome:
    """Run one capability's computation: its JSON, or the error outcome.

    A planning failure answers the failed plan-result JSON when ``plan_robot`` gives the plan's robot JSON,
    else the short failed body. A ``ValueError``/``ArithmeticError`` that is not a sphereplan error means
    the request's numbers took the computation outside its domain (or produced NaN): answered as bad
    input, logged with the traceback so the unchecked case can be turned into a named error in ``planner/``.
    """
    try:
        return ok_outcome(compute())
    except PlanningError as exc:
        return outcome_of_exception(exc, plan_robot() if plan_robot is not None else None)
    except SpherePlanError as exc:
        return outcome_of_exception(exc)
    except MemoryError:
        log.warning("%s: the job reached the per-worker memory ceiling", name)
        return error_outcome(InvalidInput, f"the {name} computation needs more memory than this server allows "
                                           "per job; ask for less (a coarser grid, fewer states, a closer goal)")
    except RecursionError:
        return error_outcome(InvalidInput, f"the {name} input is nested too deeply")
    except (ValueError, ArithmeticError) as exc:
        log.warning("%s: computation failed for a request", name, exc_info=True)
        return error_outcome(InvalidInput, f"the {name} computation failed for this input: {type(exc).__name__}: {exc}")
    except Exception as exc:  # a bug, not the client's fault: log it and answer 500
        log.exception("%s job failed", name)
        return outcome_of_exception(exc)


def plan_job(query: PlanQuery, robot: RobotProfile, source: Path | InlineGrid) -> Outcome:
    """One plan, the pipeline of ``sphereplan plan``: load the grid, attach this worker's cancel flag to the
    query's termination, then :func:`service.pipeline.execute_plan`. ``robot`` is the profile the door loaded."""

    def compute() -> dict[str, Any]:
        grid = load_grid(source, robot)  # not counted: cached per worker, a mesh's first load is slow
        mine = replace(query, termination=query.termination.with_cancel(cancelled))
        return execute_plan(mine, grid, robot).to_json()

    return _job("plan", compute, plan_robot=robot.to_json)


def simulate_job(plan: dict[str, Any], source: Path | InlineGrid, robot_name: str, seed: int, noise: str,
                 options: SimulationOptions, termination: Termination) -> Outcome:
    """``simulate_plan`` of a plan result (what ``sphereplan simulate`` writes), stopped at ``termination``
    (wall clock; this worker's cancel flag attached)."""
    from planner.closed_loop.simulate import simulate_plan

    outcome = _job("simulate", lambda: simulate_plan(load_grid(source, None), plan, load_robot(robot_name),
                                                     seed=seed, noise=noise, options=options,
                                                     termination=termination.with_cancel(cancelled)))
    if outcome.ok and outcome.json()["status"] != "reached":  # the robot failed: answered as a failure is
        return Outcome(answer_for(PlanningError), outcome.body, UNKNOWN_ERROR_CODE)
    return outcome


def reconfigure_job(problem: ReconfigureRequest, source: Path | InlineGrid | None, termination: Termination
                    ) -> Outcome:
    """``plan_reconfiguration``, checked against the grid when there is one (what ``sphereplan reconfigure``
    prints), stopped at ``termination``."""
    from planner.spherobot.reconfigure import plan_reconfiguration

    return _job("reconfigure", lambda: plan_reconfiguration(
        problem, grid=None if source is None else load_grid(source, None),
        termination=termination.with_cancel(cancelled)))


def tensegrity_static_job(theta1: float, theta2: float, robot_name: str, verify: bool) -> Outcome:
    """``static_equilibria`` (what ``sphereplan tensegrity static`` prints); angles in radians."""
    from planner.tensegrity import static_equilibria

    return _job("tensegrity", lambda: static_equilibria(theta1, theta2, load_robot(robot_name), verify))


def vpip_rods_job(phi_vpip: float, theta_vpip: float, roll: float, pitch_phase: float, robot_name: str) -> Outcome:
    """``rods_report`` (what ``sphereplan vpip rods`` prints); angles in radians."""
    from planner.vpip.api import rods_report

    return _job("vpip rods", lambda: rods_report(phi_vpip, theta_vpip, roll, pitch_phase, robot_name))


def vpip_schedule_job(plan: dict[str, Any], robot_name: str, driver: str, termination: Termination) -> Outcome:
    """``schedule_report`` of a plan result (the series ``sphereplan vpip schedule --out`` writes), stopped at
    ``termination``."""
    from planner.vpip.api import schedule_report

    outcome = _job("vpip schedule", lambda: schedule_report(plan, robot_name, driver,
                                                            termination=termination.with_cancel(cancelled)))
    if outcome.ok and not outcome.json()["summary"]["reached_end"]:  # as the CLI's exit 3: a failure, with its series
        return Outcome(answer_for(PlanningError), outcome.body, UNKNOWN_ERROR_CODE)
    return outcome


def perceive_job(left: np.ndarray, right: np.ndarray, left_info: Any, right_info: Any,
                 pose: tuple[float, float, float], roll: float, pitch: float, robot_name: str | None,
                 obstacles: Any) -> Outcome:
    """``perceive`` of one stereo pair (what ``sphereplan perceive`` prints); angles in radians."""
    from planner.perception.stereo import perceive

    def compute() -> dict[str, Any]:
        robot = load_robot(robot_name)
        scan = perceive(left, right, left_info, right_info, pose, roll, pitch, robot.radius_m,
                        obstacles=obstacles, fields=PERCEIVE_FIELDS)
        return {**scan.to_json(), "robot": {"name": robot.name, "radius_m": robot.radius_m}}

    return _job("perceive", compute)
