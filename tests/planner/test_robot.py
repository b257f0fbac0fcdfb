"""Robot profiles and the roll→curvature models."""

import math
from pathlib import Path

import numpy as np
import pytest

from planner.errors import NotFound, RobotProfileError
from planner.robot import builtin_robots, load_robot


def test_builtins_load():
    assert {"zju-60", "zju-80", "daedalus"} <= set(builtin_robots())
    r = load_robot()
    assert r.name == "zju-60" and r.radius_m == 0.30 and math.isclose(r.max_roll_rad, math.radians(15))
    assert math.isclose(r.min_turning_radius_m, 0.30 / math.tan(math.radians(15)))
    assert load_robot("zju-80").radius_m == 0.40


def test_calibrated_table_reproduces_paper_000_runs_and_round_trips():
    d = load_robot("daedalus")
    for deg, diameter in ((5, 2.6), (10, 2.0), (15, 1.7)):
        assert math.isclose(d.roll_model.turning_radius(math.radians(deg)) * 2, diameter, rel_tol=1e-9)
    k = np.linspace(-1.1, 1.1, 41)
    assert np.allclose(d.roll_model.curvature(d.roll_model.roll_for_curvature(k)), k, atol=1e-3)
    # beyond the measured range the curvature is held, never extrapolated
    assert d.roll_model.curvature(math.radians(25)) == pytest.approx(1 / 0.85)


def test_kinematic_model_is_tan_over_r():
    r = load_robot()
    assert r.roll_model.curvature(0.2) == pytest.approx(math.tan(0.2) / 0.3)
    assert r.roll_model.roll_for_curvature(math.tan(0.2) / 0.3) == pytest.approx(0.2)


def test_user_profile_and_errors(tmp_path):
    good = tmp_path / "mine.toml"
    good.write_text(
        'radius_m = 0.5\nmax_roll_deg = 10\nmax_roll_rate_deg_s = 20\nroll_time_constant_s = 0.2\n'
        'max_speed_m_s = 1\nmax_accel_m_s2 = 1\nfootprint_length_m = 1\nfootprint_width_m = 1\n'
    )
    assert load_robot(str(good)).name == "mine"
    bad = tmp_path / "bad.toml"
    bad.write_text(good.read_text().replace("radius_m = 0.5", "radius_m = -1"))
    with pytest.raises(RobotProfileError, match="radius_m"):
        load_robot(str(bad))
    bad.write_text(good.read_text().replace("max_roll_deg = 10\n", ""))
    with pytest.raises(RobotProfileError, match="max_roll_deg"):
        load_robot(str(bad))
    bad.write_text("radius_m = [")
    with pytest.raises(RobotProfileError, match="TOML"):
        load_robot(str(bad))
    with pytest.raises(NotFound, match="robot"):
        load_robot("no-such-robot")


def test_calibrated_model_between_the_measured_runs():
    """Between the paper's runs the radius falls monotonically and stays inside the bracketing runs; below
    the first run it grows without bound towards upright (κ → 0)."""
    model = load_robot("daedalus").roll_model
    rolls = np.radians(np.linspace(0.5, 15.0, 300))
    radii = np.array([model.turning_radius(r) for r in rolls])
    assert np.all(np.diff(radii) < 0)
    for lo, hi, r_lo, r_hi in ((5, 10, 1.3, 1.0), (10, 15, 1.0, 0.85)):
        inside = (rolls > math.radians(lo)) & (rolls < math.radians(hi))
        assert np.all((radii[inside] < r_lo) & (radii[inside] > r_hi))
    assert model.turning_radius(math.radians(0.5)) > 2 * model.turning_radius(math.radians(2.0))
    assert model.turning_radius(0.0) == math.inf


def _inside(poly: np.ndarray, pts: np.ndarray) -> np.ndarray:
    """Even-odd point-in-polygon, written here apart from the planner's own code."""
    x, y = pts[:, 0:1], pts[:, 1:2]
    x1, y1 = poly[:, 0], poly[:, 1]
    x2, y2 = np.roll(x1, -1), np.roll(y1, -1)
    crosses = ((y1 > y) != (y2 > y)) & (x < (x2 - x1) * (y - y1) / (y2 - y1 + 1e-300) + x1)
    return crosses.sum(axis=1) % 2 == 1


def test_default_footprint_is_a_padded_polygon_around_the_shell_ellipse() -> None:
    robot = load_robot("zju-60")
    poly = robot.footprint_polygon
    t = np.linspace(0, 2 * np.pi, 720, endpoint=False)
    ellipse = np.column_stack([0.3 * np.cos(t), 0.35 * np.sin(t)])
    assert _inside(poly, 0.999 * ellipse).all()
    # padded by 2 cm: the extents grow by the padding and no more than √2 of it
    assert 0.3 + 0.02 <= np.abs(poly[:, 0]).max() <= 0.3 / np.cos(np.pi / 16) + 0.02 + 1e-9
    assert robot.reversible and robot.preferred_clearance_m == 0.3
    js = robot.to_json()
    assert js["footprint_padding_m"] == 0.02 and len(js["footprint"]) == 16 and js["reversible"] is True


def test_a_polygon_footprint_sets_the_extents_and_is_validated(tmp_path) -> None:
    base = Path(__file__).resolve().parents[2] / "planner" / "robots" / "zju-60.toml"
    text = base.read_text().replace("footprint_length_m = 0.60", "footprint = [[0.4, 0.25], [-0.4, 0.25], "
                                    "[-0.4, -0.25], [0.4, -0.25]]").replace("footprint_width_m = 0.70", "")
    ok = tmp_path / "box.toml"
    ok.write_text(text)
    robot = load_robot(ok)
    assert robot.footprint_length_m == 0.8 and robot.footprint_width_m == 0.5
    assert np.allclose(np.abs(robot.footprint_polygon), [0.42, 0.27])
    for bad, field in [
        ("[[0.4, 0.25], [-0.4, 0.25]]", "footprint"),
        ("[[0.4, 0.25], [-0.4, -0.25], [-0.4, 0.25], [0.4, -0.25]]", "footprint"),  # a bow tie
        ("[[1.0, 1.0], [2.0, 1.0], [2.0, 2.0]]", "footprint"),  # does not surround the centre
        ("[[0.4, 0.25], [-0.4, 0.25], [\"a\", 0]]", "footprint[2]"),
    ]:
        p = tmp_path / "bad.toml"
        p.write_text(text.replace("[[0.4, 0.25], [-0.4, 0.25], [-0.4, -0.25], [0.4, -0.25]]", bad))
        with pytest.raises(RobotProfileError) as info:
            load_robot(p)
        assert info.value.field == field
    p = tmp_path / "neg.toml"
    p.write_text(text.replace("footprint_padding_m = 0.02", "footprint_padding_m = -0.1"))
    with pytest.raises(RobotProfileError, match="footprint_padding_m"):
        load_robot(p)
