"""PlanningService in-process: settings, map lookup, error mapping, the in-flight cap, the pool life cycle."""

from __future__ import annotations

import io
import json
from concurrent.futures import Executor, Future, ThreadPoolExecutor
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from PIL import Image
from pydantic import ValidationError

from planner.errors import GoalOccupied, InvalidInput, NotFound, PlannerTimedOut
from planner.maps.catalogue import map_files
from planner.occupancy import OccupancyGrid
from service.core import PlanningService
from service.grids import grid_png, inline_grid
from service.outcome import ServiceBusy, ok_outcome, outcome_of_exception
from service.settings import ServiceSettings
from service.wire import InlineGrid, PlanRequest, field_name, invalid_input
from tests.service import service_harness as harness
from tests.service.service_harness import plan_body, strip_timing


@pytest.fixture(scope="module")
def maps_dir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    folder = harness.make_maps(tmp_path_factory.mktemp("maps"))
    (folder / ".hidden.yaml").write_text("image: x.pgm\n")
    (folder / "notes.txt").write_text("not a map\n")
    return folder


class NeverDone(Executor):
    """An executor whose jobs never finish (until ``finish_all``): fills the in-flight cap on demand."""

    def __init__(self, workers: int = 1) -> None:
        self.futures: list[Future[Any]] = []

    def submit(self, fn: Any, /, *args: Any, **kwargs: Any) -> Future[Any]:
        future: Future[Any] = Future()
        self.futures.append(future)
        return future

    def finish_all(self) -> None:
        for future in self.futures:
            future.set_result(ok_outcome({}))


def test_settings_are_validated_by_field(tmp_path: Path) -> None:
    with pytest.raises(InvalidInput) as err:
        ServiceSettings(workers=0)
    assert err.value.field == "workers"
    with pytest.raises(InvalidInput) as err:
        ServiceSettings(max_time_limit_s=float("nan"))
    assert err.value.field == "max_time_limit_s"
    with pytest.raises(InvalidInput) as err:
        ServiceSettings(zenoh_config=tmp_path / "missing.json5")
    assert err.value.field == "zenoh_config"
    assert ServiceSettings(workers=3).in_flight_cap == 12
    assert ServiceSettings(workers=3, max_in_flight=5).in_flight_cap == 5


def test_map_names_only_reach_maps_in_the_folder(maps_dir: Path) -> None:
    assert map_files(maps_dir) == {"hall": maps_dir / "hall.yaml"}
    service = PlanningService(ServiceSettings(maps_dir=maps_dir, zenoh=False), NeverDone)
    assert service.resolve_map("hall") == maps_dir / "hall.yaml"
    for name in ("..", "../maps/hall", "hall.yaml", ".hidden", "notes", str(maps_dir / "hall")):
        with pytest.raises(NotFound) as err:
            service.resolve_map(name)
        assert err.value.field == "map"
    with pytest.raises(ValidationError):
        PlanRequest.model_validate({**plan_body(), "map": "../maps/hall"})
    assert service.maps() == [{"name": "hall", "file": "hall.yaml", "kind": "grid", "size_m": [10.0, 8.0],
                               "resolution_m": 0.1}]


def test_robot_names_are_built_in_profiles_only(maps_dir: Path) -> None:
    service = PlanningService(ServiceSettings(maps_dir=maps_dir, zenoh=False), NeverDone)
    service.resolve_robot("zju-80")
    service.resolve_robot(None)
    for name in ("wheelie", "zju-60.toml"):
        with pytest.raises(NotFound):
            service.resolve_robot(name)


def test_errors_map_onto_outcomes() -> None:
    timeout = outcome_of_exception(PlannerTimedOut("too slow"), {"name": "zju-60"})
    assert timeout.kind == "failed" and timeout.error_code == 207
    body = timeout.json()
    assert body["status"] == "failed" and body["error_code"] == 207 and body["robot"] == {"name": "zju-60"}
    assert outcome_of_exception(GoalOccupied("in a wall")).json()["error_code"] == 206
    missing = outcome_of_exception(NotFound("map", "no map named 'x'"))
    assert missing.kind == "not_found" and missing.json() == {"error_code": 200, "error_msg": "map: no map named 'x'",
                                                              "field": "map"}
    assert outcome_of_exception(InvalidInput("options.greed", "must be ≥ 0")).kind == "bad_input"
    assert outcome_of_exception(RuntimeError("bug")).kind == "internal"


def test_field_names_of_validation_errors() -> None:
    assert field_name(("body", "map", "InlineGrid", "data", 3, 1)) == "map.data[3][1]"
    assert field_name(("options", "greed", "bool")) == "options.greed"
    with pytest.raises(ValidationError) as err:
        PlanRequest.model_validate({**plan_body(), "map": "../x"})
    error = invalid_input(err.value.errors())
    assert error.field == "map" and "pattern" in str(error)  # the name rule, not "should be an object"


def test_in_flight_cap_gives_busy_and_frees_on_completion(maps_dir: Path) -> None:
    executors: list[NeverDone] = []

    def factory(workers: int) -> Executor:
        executors.append(NeverDone())
        return executors[-1]

    service = PlanningService(ServiceSettings(maps_dir=maps_dir, workers=1, max_in_flight=2, zenoh=False,
                                              warm_up=False), factory)
    request = PlanRequest.model_validate(plan_body())
    with pytest.raises(ServiceBusy):  # not started yet
        service.submit_plan(request)
    service.start()
    assert service.ready
    pending = [service.submit_plan(request), service.submit_plan(request)]
    assert service.in_flight == 2
    with pytest.raises(ServiceBusy) as err:
        service.submit_plan(request)
    assert outcome_of_exception(err.value).kind == "busy" and err.value.retry_after_s == 1
    assert service.plan(request).kind == "busy"
    executors[0].finish_all()
    assert [p.result(timeout=1).kind for p in pending] == ["ok", "ok"]
    assert service.in_flight == 0
    service.submit_plan(request)
    service.close()
    service.close()  # idempotent
    assert not service.ready
    with pytest.raises(ServiceBusy):
        service.submit_plan(request)


def test_request_errors_are_raised_before_a_job_is_queued(maps_dir: Path) -> None:
    executor = NeverDone()
    service = PlanningService(ServiceSettings(maps_dir=maps_dir, max_time_limit_s=2.0, zenoh=False, warm_up=False),
                              lambda workers: executor)
    service.start()
    bad = [({**plan_body(), "map": "nowhere"}, NotFound, "map"),
           (plan_body(robot="wheelie"), NotFound, "robot"),
           (plan_body(options={"n_rolls": 4}), InvalidInput, "options.n_rolls"),
           (plan_body(time_limit_s=5.0), InvalidInput, "time_limit_s"),
           (plan_body(options={"time_limit_s": 5.0}), InvalidInput, "options.time_limit_s")]
    for body, error, field in bad:
        with pytest.raises(error) as err:
            service.submit_plan(PlanRequest.model_validate(body))
        assert err.value.field == field  # type: ignore[attr-defined]
    assert executor.futures == [] and service.in_flight == 0
    service.close()


def test_plan_in_a_thread_pool_matches_the_planner(maps_dir: Path) -> None:
    """The job function itself (run here in a thread): same result as the planner API directly."""
    from planner.hybrid_astar.plan import plan_path
    from planner.robot import load_robot

    service = PlanningService(ServiceSettings(maps_dir=maps_dir, zenoh=False, warm_up=False), ThreadPoolExecutor)
    service.start()
    try:
        outcome = service.plan(PlanRequest.model_validate(plan_body()), timeout_s=60)
        slow = plan_body(goal=harness.SLOT_GOAL, options=harness.SLOW, time_limit_s=0.2)
        slot = service.plan(PlanRequest.model_validate(slow), timeout_s=60)
    finally:
        service.close()
    assert outcome.ok, outcome.body
    direct = plan_path(harness.hall_grid(), load_robot(None), harness.HALL_START, harness.HALL_GOAL)
    assert strip_timing(outcome.json()) == strip_timing(json.loads(json.dumps(direct.to_json())))
    assert slot.kind == "failed" and slot.error_code == 207 and slot.json()["robot"]["name"] == "zju-60"


def test_inline_grids_are_cached_by_content() -> None:
    spec = {"data": [[0, 0, 100], [0, -1, 0]], "resolution_m": 0.5, "origin": [1.0, 2.0, 0.0], "name": "tiny"}
    grid = inline_grid(InlineGrid.model_validate(spec))
    assert grid is inline_grid(InlineGrid.model_validate(json.loads(json.dumps(spec))))
    assert grid.data.dtype == np.int8 and grid.data[0, 2] == 100 and grid.origin == (1.0, 2.0, 0.0)
    assert grid is not inline_grid(InlineGrid.model_validate({**spec, "resolution_m": 0.25}))


def test_map_png_is_north_up_with_map_server_shades() -> None:
    data = np.array([[0, 100], [-1, 50]], dtype=np.int8)  # row 0 is the bottom
    png = grid_png(OccupancyGrid(data=data, resolution_m=1.0))
    with Image.open(io.BytesIO(png)) as image:
        assert image.mode == "L" and image.size == (2, 2)
        assert np.asarray(image).tolist() == [[205, 127], [254, 0]]


def test_a_budget_past_the_time_limit_answers_with_the_best_path() -> None:
    """Issue 21 item 6: the doors count the whole plan against its time limit (service/pipeline.py); with
    improve_until_s past the limit the improvement rounds end early enough that the best path is the answer, not a
    timeout. (The two-walls problem's greed-0 search does not end within seconds, so the limit is what stops it.)"""
    import itertools
    import math

    from planner.hybrid_astar.search import PlannerOptions
    from planner.robot import load_robot
    from planner.termination import Termination
    from service.pipeline import PlanQuery, execute_plan
    from tests.planner.hybrid_astar.test_search import two_walls
    from tests.scenarios import SCENARIO_BINS

    # (72 heading bins, 11 held rolls and a closed-set bin per roll: the greed-0 search then takes about 18 s on the
    # 2-core machine of issue 21's seventeenth round, where 72 bins alone took 2.3 s and ended inside the limit once
    # the search got faster; the first path still comes in 15 ms, so the limit is what stops the rounds on a machine
    # five times faster or one a few times slower)
    query = PlanQuery((2.0, 2.0, 0.0), (18.0, 18.0, math.pi / 2),
                      PlannerOptions(improve_until_s=600.0, n_yaw_bins=SCENARIO_BINS, n_rolls=11, n_roll_bins=0),
                      Termination(3.0))  # (the rounds end 10 % early: 0.3 s of room for a loaded machine)
    result = execute_plan(query, two_walls(), load_robot())
    assert result.extra["improvement_stop"] == "time limit"
    assert result.planning_time_s < 3.0
    # the answer is the best path the rounds kept (the first, then whatever beat it: since the search sweeps lazily
    # the greed 0.5 and 0.25 rounds' paths are longer than the first here, and only the last smoothing, when the
    # greed-0 search leaves it time before the limit, shortens it, so how many are listed depends on the machine)
    kept = result.extra["improvements"]
    assert kept[0]["by"] == "first path" and all(b["cost"] < a["cost"] for a, b in itertools.pairwise(kept))
    assert result.length_m == pytest.approx(kept[-1]["length_m"], abs=1e-3)  # (states vs motions: sub-mm)
