"""MCAP out (``--out X.mcap``) and maps in from MCAP / rosbag2, checked with an independent decoder.

The files are written with ``mcap-ros2-support`` (its own CDR encoder); every test reads them back with the
plain ``mcap`` reader and decodes the CDR with ``rosbags``' type store (a separate CDR implementation with
its own copy of the ROS 2 Humble message definitions), so a field layout mistake shows up here.
"""

import itertools
import json
import math

import numpy as np
import pytest
from mcap.reader import make_reader
from rosbags.typesys import Stores, get_typestore

from planner.maps.catalogue import default_maps_dir
from planner.maps.load import load_any
from service.cli import main

GARAGE = str(default_maps_dir() / "garage.yaml")
TS = get_typestore(Stores.ROS2_HUMBLE)


def decode(path):
    """``{topic: [(log_time_ns, schema name, message)]}`` decoded by rosbags from the raw CDR."""
    out = {}
    with open(path, "rb") as f:
        reader = make_reader(f)
        header = reader.get_header()
        assert header.profile == "ros2"
        for schema, channel, message in reader.iter_messages(log_time_order=True):
            assert schema.encoding == "ros2msg" and channel.message_encoding == "cdr"
            out.setdefault(channel.topic, []).append(
                (message.log_time, schema.name, TS.deserialize_cdr(message.data, schema.name)))
    return out


def sec(stamp):
    return stamp.sec + stamp.nanosec * 1e-9


def yaw(q):
    return math.atan2(2 * (q.w * q.z + q.x * q.y), 1 - 2 * (q.y * q.y + q.z * q.z))


def run(capsys, *argv):
    code = main(list(argv))
    out = capsys.readouterr()
    return code, out.out, out.err


@pytest.fixture(scope="module")
def plan_mcap(tmp_path_factory):
    path = tmp_path_factory.mktemp("mcap") / "plan.mcap"
    code = main(["plan", "--map", GARAGE, "--start", "3.5", "8.05", "0", "--goal", "12", "8.05", "0",
                 "--out", str(path), "--robot", "zju-60"])
    assert code == 0
    return path


def test_plan_mcap_holds_map_path_and_footprints(plan_mcap, capsys):
    code, stdout, _ = run(capsys, "plan", "--map", GARAGE, "--start", "3.5", "8.05", "0", "--goal", "12", "8.05",
                          "0", "--out", str(plan_mcap.with_name("again.mcap")))
    assert code == 0
    plan = json.loads(stdout)  # with --out X.mcap the JSON still goes to stdout
    msgs = decode(plan_mcap.with_name("again.mcap"))
    assert {"/map", "/plan", "/plan/footprints", "/plan/start", "/plan/goal"} <= set(msgs)

    # /map: the garage grid, row-major, row 0 at the origin
    (_, typename, grid_msg), = msgs["/map"]
    assert typename == "nav_msgs/msg/OccupancyGrid"
    grid = load_any(GARAGE)
    info = grid_msg.info
    assert (info.width, info.height) == (grid.width, grid.height)
    assert info.resolution == pytest.approx(grid.resolution_m)
    assert (info.origin.position.x, info.origin.position.y) == pytest.approx(grid.origin[:2])
    assert grid_msg.header.frame_id == "map"
    np.testing.assert_array_equal(np.asarray(grid_msg.data).reshape(info.height, info.width), grid.data)

    # /plan: one stamped pose per state, at the plan's times
    (t_log, typename, path), = msgs["/plan"]
    assert typename == "nav_msgs/msg/Path"
    states = plan["states"]
    assert len(path.poses) == len(states)
    t0 = sec(path.header.stamp)
    assert t_log == pytest.approx(t0 * 1e9, abs=1e3)
    for ps, st in zip(path.poses, states, strict=True):
        assert ps.header.frame_id == "map"
        assert (ps.pose.position.x, ps.pose.position.y) == pytest.approx((st["x"], st["y"]))
        assert math.remainder(yaw(ps.pose.orientation) - st["yaw"], math.tau) == pytest.approx(0, abs=1e-9)
        assert sec(ps.header.stamp) - t0 == pytest.approx(st["t"], abs=1e-6)

    # /plan/footprints: the profile's padded footprint polygon along the path, plus the path line
    (_, typename, markers), = msgs["/plan/footprints"]
    assert typename == "visualization_msgs/msg/MarkerArray"
    rects = [m for m in markers.markers if m.ns == "footprints"]
    line = [m for m in markers.markers if m.ns == "path"]
    assert 0.7 * plan["length_m"] / 0.25 <= len(rects) <= plan["length_m"] / 0.25 + 2 and len(line) == 1
    assert len(line[0].points) == len(states) and len(line[0].colors) == len(states)
    polygon = plan["robot"]["footprint"]
    edges = [math.dist(a, b) for a, b in zip(polygon, polygon[1:] + polygon[:1], strict=True)]
    for m in rects:
        assert m.type == 4 and m.action == 0 and len(m.points) == len(polygon) + 1
        p = [(q.x, q.y) for q in m.points]
        assert p[0] == pytest.approx(p[-1])
        assert [math.dist(a, b) for a, b in itertools.pairwise(p)] == pytest.approx(edges, abs=1e-5)
    assert {m.id for m in rects} == set(range(len(rects)))

    (_, _, start), = msgs["/plan/start"]
    assert (start.pose.position.x, start.pose.position.y) == pytest.approx((3.5, 8.05))


def test_plan_reads_its_map_back_from_the_mcap(plan_mcap, capsys):
    code, stdout, _ = run(capsys, "plan", "--map", str(plan_mcap), "--map-topic", "/map", "--start", "3.5", "8.05",
                          "0", "--goal", "12", "8.05", "0")
    assert code == 0
    assert json.loads(stdout)["status"] == "exact"


def test_plan_reads_its_map_from_a_rosbag2_folder(tmp_path, capsys):
    """A rosbag2 folder written by rosbags (sqlite3 storage, as ``ros2 bag record`` writes by default)."""
    from rosbags.rosbag2 import Writer

    grid = load_any(GARAGE)
    msg_t = TS.types["nav_msgs/msg/OccupancyGrid"]
    Header, Time = TS.types["std_msgs/msg/Header"], TS.types["builtin_interfaces/msg/Time"]
    MapMetaData, Pose = TS.types["nav_msgs/msg/MapMetaData"], TS.types["geometry_msgs/msg/Pose"]
    Point, Quaternion = TS.types["geometry_msgs/msg/Point"], TS.types["geometry_msgs/msg/Quaternion"]
    msg = msg_t(header=Header(stamp=Time(sec=1, nanosec=0), frame_id="map"),
                info=MapMetaData(map_load_time=Time(sec=1, nanosec=0), resolution=grid.resolution_m,
                                 width=grid.width, height=grid.height,
                                 origin=Pose(position=Point(x=grid.origin[0], y=grid.origin[1], z=0.0),
                                             orientation=Quaternion(x=0.0, y=0.0, z=0.0, w=1.0))),
                data=np.asarray(grid.data, dtype=np.int8).ravel())
    bag = tmp_path / "run_bag"
    with Writer(bag, version=8) as writer:
        conn = writer.add_connection("/robot/map", "nav_msgs/msg/OccupancyGrid", typestore=TS)
        writer.write(conn, 1_000_000_000, TS.serialize_cdr(msg, "nav_msgs/msg/OccupancyGrid"))
    code, stdout, _ = run(capsys, "plan", "--map", str(bag), "--map-topic", "/robot/map", "--start", "3.5", "8.05",
                          "0", "--goal", "12", "8.05", "0")
    assert code == 0 and json.loads(stdout)["status"] == "exact"

    code, _, err = run(capsys, "plan", "--map", str(bag), "--start", "3.5", "8.05", "0", "--goal", "12", "8.05", "0")
    assert code == 2 and "--map-topic" in err and "/robot/map" in err


@pytest.mark.parametrize("argv, field", [
    (["--map-topic", "/nope"], "--map-topic"),
    (["--map-topic", "/plan"], "--map-topic"),
])
def test_bad_map_topic_is_bad_input(plan_mcap, capsys, argv, field):
    code, _, err = run(capsys, "plan", "--map", str(plan_mcap), *argv, "--start", "3.5", "8.05", "0",
                       "--goal", "12", "8.05", "0")
    assert code == 2 and field in err


def test_not_an_mcap_is_bad_input(tmp_path, capsys):
    bad = tmp_path / "x.mcap"
    bad.write_bytes(b"not an mcap file")
    code, _, err = run(capsys, "plan", "--map", str(bad), "--start", "3.5", "8.05", "0", "--goal", "12", "8.05", "0")
    assert code == 2 and "--map" in err
    code, _, err = run(capsys, "plan", "--map", GARAGE, "--map-topic", "/map", "--start", "3.5", "8.05", "0",
                       "--goal", "12", "8.05", "0")
    assert code == 2 and "--map-topic" in err


@pytest.fixture(scope="module")
def plan_json(tmp_path_factory):
    path = tmp_path_factory.mktemp("plan") / "plan.json"
    assert main(["plan", "--map", GARAGE, "--start", "3.5", "8.05", "0", "--goal", "12", "8.05", "0",
                 "--out", str(path)]) == 0
    return path


def test_simulation_mcap_holds_executed_and_estimated_poses(plan_json, tmp_path, capsys):
    out = tmp_path / "sim.mcap"
    code, stdout, _ = run(capsys, "simulate", "--map", GARAGE, "--path", str(plan_json), "--noise", "none",
                          "--tracker", "pursuit", "--out", str(out))
    assert code == 0
    sim = json.loads(stdout)
    msgs = decode(out)
    assert {"/map", "/plan", "/plan/footprints", "/sim/pose", "/sim/estimate", "/sim/trajectory",
            "/sim/estimate/path"} <= set(msgs)
    poses = msgs["/sim/pose"]
    assert len(poses) == len(sim["trajectory"])
    t0 = sec(msgs["/plan"][0][2].header.stamp)
    for (t_log, typename, ps), row in zip(poses, sim["trajectory"], strict=True):
        assert typename == "geometry_msgs/msg/PoseStamped"
        assert (ps.pose.position.x, ps.pose.position.y) == pytest.approx((row["x"], row["y"]))
        assert sec(ps.header.stamp) - t0 == pytest.approx(row["t"], abs=1e-6)
        assert t_log == pytest.approx((t0 + row["t"]) * 1e9, abs=2e3)
    assert [m[0] for m in poses] == sorted(m[0] for m in poses)  # replayable in time
    est = msgs["/sim/estimate/path"][0][2]
    assert len(est.poses) == len(sim["estimate"])
    assert est.poses[-1].pose.position.x == pytest.approx(sim["estimate"][-1]["x"])


def test_reconfiguration_mcap_holds_the_sphere_pose(tmp_path, capsys):
    out = tmp_path / "rec.mcap"
    code, stdout, _ = run(capsys, "reconfigure", "--start", "0", "0", "--start-tilt", "30", "75", "--degrees",
                          "--goal", "1.5", "1.0", "--out", str(out))
    assert code == 0
    rec = json.loads(stdout)
    msgs = decode(out)
    poses = msgs["/reconfigure/pose"]
    assert len(poses) == len(rec["samples"]) and "/map" not in msgs
    last = poses[-1][2].pose
    assert (last.position.x, last.position.y, last.position.z) == pytest.approx(
        (rec["final"]["x"], rec["final"]["y"], rec["radius_m"]))
    assert (last.orientation.w, last.orientation.x, last.orientation.y, last.orientation.z) == pytest.approx(
        (rec["final"]["qw"], rec["final"]["qx"], rec["final"]["qy"], rec["final"]["qz"]))
    assert len(msgs["/reconfigure/path"][0][2].poses) == len(rec["samples"])


def test_vpip_schedule_mcap_holds_rod_lengths(tmp_path, capsys):
    plan_json = tmp_path / "plan.json"  # planned for daedalus, so that its rods can roll it to the end
    assert main(["plan", "--map", GARAGE, "--start", "3.5", "8.05", "0", "--goal", "8", "8.05", "0",
                 "--robot", "daedalus", "--out", str(plan_json)]) == 0
    out, js = tmp_path / "sched.mcap", tmp_path / "sched.json"
    assert run(capsys, "vpip", "schedule", "--path", str(plan_json), "--robot", "daedalus", "--out", str(js))[0] == 0
    code, _, _ = run(capsys, "vpip", "schedule", "--path", str(plan_json), "--robot", "daedalus", "--out", str(out))
    assert code == 0
    schedule = json.loads(js.read_text())
    msgs = decode(out)
    rods, plane = msgs["/vpip/rods"], msgs["/vpip/plane"]
    series = schedule["series"]
    assert len(rods) == len(plane) == len(series["t"])
    i = len(rods) // 2
    msg = rods[i][2]
    assert rods[i][1] == "sensor_msgs/msg/JointState"
    assert list(msg.position) == pytest.approx(series["rod_length_m"][i])
    assert list(msg.name) == [f"rod_{r['index']}_{r['side']}" for r in schedule["rods"]]
    angles = dict(zip(plane[i][2].name, plane[i][2].position, strict=True))
    assert angles["phi_vpip_rad"] == pytest.approx(series["phi_vpip_rad"][i])
    assert "/plan" in msgs and "/vpip/pose" in msgs
