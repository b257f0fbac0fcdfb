"""The live map: Nav2 obstacle-layer marking and ray-traced clearing, paper 001's filters, unknown until seen,
region and whole-map updates, and the changed rectangle."""

from __future__ import annotations

import math

import numpy as np
import pytest

from planner.errors import InvalidInput
from planner.live import (
    LiveMap,
    ObstacleLayerParams,
    PointObservation,
    RangeSensor,
    RegionUpdate,
    ScanObservation,
    SensorPose,
)
from planner.occupancy import OccupancyGrid
from planner.robot import load_robot

ROBOT = load_robot("zju-60")


def open_grid(w: int = 200, h: int = 100, res: float = 0.1) -> OccupancyGrid:
    return OccupancyGrid.from_occupied(np.zeros((h, w), dtype=bool), res, name="open")


def cell(live: LiveMap, x: float, y: float) -> int:
    ix, iy = live.grid.world_to_cell(x, y)
    return int(live.data[iy, ix])


def test_points_mark_and_clear_along_the_ray() -> None:
    live = LiveMap.unknown(20.0, 10.0, 0.1, layer=ObstacleLayerParams.for_robot(ROBOT))
    upd = live.apply(PointObservation(np.array([[6.05, 5.05, 0.3]]), np.array([1.05, 5.05, 0.3])))
    assert cell(live, 6.05, 5.05) == 100  # the hit
    assert all(cell(live, x, 5.05) == 0 for x in np.arange(1.05, 6.0, 0.1))  # the ray, cleared
    assert cell(live, 7.05, 5.05) == -1 and cell(live, 3.05, 6.05) == -1  # unseen stays unknown
    assert upd.changed is not None and upd.cells_changed == 51
    assert upd.changed.ix0 == 10 and upd.changed.ix1 == 61 and upd.changed.iy1 - upd.changed.iy0 == 1
    # the same observation again changes nothing
    assert live.apply(PointObservation(np.array([[6.05, 5.05, 0.3]]), np.array([1.05, 5.05, 0.3]))).changed is None


def test_paper_filters_height_and_range() -> None:
    live = LiveMap(open_grid(), ObstacleLayerParams.for_robot(ROBOT))
    origin = np.array([1.0, 5.0, 0.3])
    pts = np.array([[3.0, 5.05, 0.02],     # ground: below 5 cm
                    [3.0, 6.05, 1.5],      # suspended above the sphere (diameter 0.6 m)
                    [12.5, 5.05, 0.3],     # 11.5 m away: beyond 10 m
                    [4.0, 4.05, 0.3]])     # a real obstacle
    live.apply(PointObservation(pts, origin))
    assert cell(live, 4.0, 4.05) == 100
    assert cell(live, 3.0, 5.05) == 0 and cell(live, 3.0, 6.05) == 0
    assert cell(live, 12.5, 5.05) == 0  # not marked; the ray is cut at 10 m of clearing too
    assert cell(live, 11.5, 5.05) == 0


def test_clearing_removes_an_obstacle_that_moved_but_never_a_static_wall() -> None:
    occupied = np.zeros((100, 200), dtype=bool)
    occupied[:, 150] = True  # a wall of the given map at x = 15.0 m
    live = LiveMap(OccupancyGrid.from_occupied(occupied, 0.1), ObstacleLayerParams.for_robot(ROBOT))
    live.apply(PointObservation(np.array([[8.05, 5.05, 0.3]]), np.array([1.0, 5.05, 0.3])))
    assert cell(live, 8.05, 5.05) == 100
    # the obstacle left: a ray through its cell to the far wall clears it; the wall stays
    live.apply(PointObservation(np.array([[15.05, 5.05, 0.3]]), np.array([6.0, 5.05, 0.3])))
    assert cell(live, 8.05, 5.05) == 0
    live.apply(PointObservation(np.array([[17.0, 5.05, 0.3]]), np.array([12.0, 5.05, 0.3])))
    assert cell(live, 15.05, 5.05) == 100


def test_sensor_frame_points_are_transformed() -> None:
    live = LiveMap(open_grid(), ObstacleLayerParams.for_robot(ROBOT))
    sensor = SensorPose(5.0, 5.0, 0.3, yaw=math.pi / 2)
    live.apply(PointObservation.in_sensor_frame(np.array([[2.0, 0.0, 0.0]]), sensor))  # 2 m ahead = +y in map
    assert cell(live, 5.0, 7.0) == 100


def test_scan_marks_returns_and_clears_no_return_beams() -> None:
    live = LiveMap.unknown(20.0, 20.0, 0.1, layer=ObstacleLayerParams.for_robot(ROBOT))
    scan = ScanObservation(np.array([3.0, np.inf]), 0.0, math.pi / 2, 0.1, 8.0, SensorPose(10.0, 10.0, 0.3))
    live.apply(scan)
    assert cell(live, 13.0, 10.0) == 100
    assert cell(live, 10.0, 17.5) == 0  # no return: cleared up to range_max (inf_is_valid)
    assert cell(live, 10.0, 18.5) == -1


def test_simulated_sensor_sees_the_true_world() -> None:
    occupied = np.zeros((100, 100), dtype=bool)
    occupied[:, 70] = True
    world = OccupancyGrid.from_occupied(occupied, 0.1)
    sensor = RangeSensor(range_m=10.0, n_beams=360, noise_m=0.0)
    scan = sensor.scan(world, (2.0, 5.0, 0.0), np.random.default_rng(0))
    assert scan.ranges_m[0] == pytest.approx(5.05, abs=1e-9)  # half a cell into the wall at x = 7.0
    live = LiveMap.unknown(10.0, 10.0, 0.1, layer=ObstacleLayerParams.for_robot(ROBOT))
    live.apply(scan)
    assert cell(live, 7.05, 5.0) == 100 and cell(live, 5.0, 5.0) == 0
    assert live.known_fraction() > 0.3


def test_region_and_whole_map_updates() -> None:
    live = LiveMap(open_grid(), ObstacleLayerParams.for_robot(ROBOT))
    upd = live.apply(RegionUpdate(10, 20, np.full((3, 4), 100)))
    assert upd.changed is not None and (upd.changed.ix0, upd.changed.iy0, upd.changed.ix1, upd.changed.iy1) == \
        (10, 20, 14, 23)
    assert cell(live, 1.05, 2.05) == 100
    upd = live.replace(open_grid())
    assert upd.cells_changed == 12 and int(live.data.max()) == 0
    with pytest.raises(InvalidInput) as err:
        live.apply(RegionUpdate(199, 0, np.zeros((1, 2))))
    assert err.value.field == "data"
    with pytest.raises(InvalidInput) as err:
        live.replace(open_grid(w=50))
    assert err.value.field == "map"


def test_bad_observations_name_the_field() -> None:
    with pytest.raises(InvalidInput) as err:
        PointObservation(np.zeros((4, 2)), np.zeros(3))
    assert err.value.field == "points"
    with pytest.raises(InvalidInput) as err:
        PointObservation(np.array([[0.0, 0.0, np.nan]]), np.zeros(3))
    assert err.value.field == "points"
    with pytest.raises(InvalidInput) as err:
        SensorPose(0.0, 0.0, yaw=90.0)
    assert err.value.field == "sensor_pose.yaw"
    with pytest.raises(InvalidInput) as err:
        ScanObservation(np.array([1.0]), 0.0, 0.1, 2.0, 1.0, SensorPose(0.0, 0.0))
    assert err.value.field == "range_max"


def test_observation_angles_follow_the_one_angle_rule_naming_the_field() -> None:
    """Scans, sensor poses and session poses refuse degrees given as radians by planner.angles' rule, naming
    the very field that is wrong."""
    import pytest as _pytest

    from planner.errors import InvalidInput
    from planner.live.observations import ScanObservation, SensorPose

    with _pytest.raises(InvalidInput) as bad_min:
        ScanObservation(ranges_m=[1.0, 1.0], angle_min_rad=-90.0, angle_increment_rad=0.01,
                        range_min_m=0.1, range_max_m=10.0, sensor=SensorPose(0.0, 0.0))
    assert bad_min.value.field == "angle_min"
    with _pytest.raises(InvalidInput) as bad_inc:
        ScanObservation(ranges_m=[1.0, 1.0], angle_min_rad=-1.0, angle_increment_rad=45.0,
                        range_min_m=0.1, range_max_m=10.0, sensor=SensorPose(0.0, 0.0))
    assert bad_inc.value.field == "angle_increment"
    with _pytest.raises(InvalidInput) as bad_yaw:
        SensorPose(0.0, 0.0, yaw=180.0)
    assert bad_yaw.value.field == "sensor_pose.yaw" and "outside [−2π, 2π]" in bad_yaw.value.msg
