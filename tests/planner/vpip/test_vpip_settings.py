"""Contact settings and gain sets of a rod-driven profile (planner/vpip/settings.py, docs/vpip.md)."""

from __future__ import annotations

import dataclasses
import math
import tomllib

import pytest

from planner.errors import InvalidInput, RobotProfileError
from planner.robot import load_robot, profile_from_dict
from planner.vpip.api import profile_toml
from planner.vpip.cascade import vpip_section
from planner.vpip.choices import CONTACTS, GAIN_SETS
from planner.vpip.controllers import ROLL_GAINS, gains_from_section
from planner.vpip.mujoco_model import BodyParams, build_mjcf
from planner.vpip.rods import RodParams
from planner.vpip.settings import setting_names, with_settings

DAEDALUS = load_robot("daedalus")


def test_the_profile_defines_every_offered_setting_and_the_defaults_are_its_own() -> None:
    section = vpip_section(DAEDALUS)
    assert set(section["contact_settings"]) == set(CONTACTS)
    assert set(section["gain_sets"]) == set(GAIN_SETS)
    assert setting_names(with_settings(DAEDALUS)) == {"contact": "regolith", "gains": "rod-rate"}


def test_paper_contact_is_the_papers_simulator_and_regolith_keeps_spin_friction() -> None:
    paper = BodyParams.from_section(vpip_section(with_settings(DAEDALUS, contact="paper")))
    regolith = BodyParams.from_section(vpip_section(with_settings(DAEDALUS, contact="regolith")))
    # Table 1: mu1/mu2 = 200/100 (the smaller, MuJoCo's friction is isotropic); Gazebo: no spin, no rolling friction
    assert (paper.ground_friction, paper.rod_tip_friction) == (100.0, 100.0)
    assert paper.ground_torsional_friction_m == 0.0 and paper.ground_rolling_friction_m == 0.0
    assert regolith.ground_friction == 1.0 and regolith.ground_torsional_friction_m == pytest.approx(0.03)
    # and the MJCF the plant builds carries them
    assert 'friction="100 0 0"' in build_mjcf(RodParams(), paper)
    assert 'friction="1 0.03 0"' in build_mjcf(RodParams(), regolith)


def test_table1_gains_stay_available_and_the_default_set_differs() -> None:
    roll, pitch, _ = gains_from_section(vpip_section(with_settings(DAEDALUS, gains="table1")))
    assert (roll.kp, roll.ki, roll.kd) == (ROLL_GAINS.kp, ROLL_GAINS.ki, ROLL_GAINS.kd)
    assert (pitch.kp, pitch.ki) == (10.1, 2.1) and pitch.integral_limit == pytest.approx(math.radians(10))
    roll, pitch, _ = gains_from_section(vpip_section(with_settings(DAEDALUS)))
    assert roll.kd < ROLL_GAINS.kd and pitch.kp < 10.1
    assert pitch.integral_limit == pytest.approx(pitch.output_limit)  # the integral may hold any theta_vpip


def test_settings_apply_once_and_a_later_choice_wins() -> None:
    once = with_settings(DAEDALUS, "paper", "table1")
    assert with_settings(once) == once  # idempotent: the names it recorded pick the same tables
    back = with_settings(once, contact="regolith")
    assert setting_names(back) == {"contact": "regolith", "gains": "table1"}
    assert vpip_section(back)["ground_torsional_friction_m"] == pytest.approx(0.03)


def test_bad_names_and_missing_tables_name_the_field() -> None:
    with pytest.raises(InvalidInput, match="contact"):
        with_settings(DAEDALUS, contact="gazebo")
    with pytest.raises(InvalidInput, match="gains"):
        with_settings(DAEDALUS, gains="tuned")
    section = {k: v for k, v in vpip_section(DAEDALUS).items() if k not in ("contact", "contact_settings")}
    bare = dataclasses.replace(DAEDALUS, extra={**DAEDALUS.extra, "vpip": section})
    assert setting_names(with_settings(bare))["contact"] is None  # nothing to choose, nothing asked: unchanged
    with pytest.raises(InvalidInput, match="contact"):
        with_settings(bare, contact="paper")
    odd = {**vpip_section(DAEDALUS), "contact_settings": {"paper": {"ground_friction": 2.0, "solref": 0.02}}}
    with pytest.raises(RobotProfileError, match=r"vpip\.contact_settings\.paper\.solref"):
        with_settings(dataclasses.replace(DAEDALUS, extra={**DAEDALUS.extra, "vpip": odd}), contact="paper")
    with pytest.raises(RobotProfileError, match=r"vpip\.contact_settings\.regolith"):
        with_settings(dataclasses.replace(DAEDALUS, extra={**DAEDALUS.extra, "vpip": odd}), contact="regolith")


def test_a_written_profile_keeps_its_settings_tables() -> None:
    text = profile_toml(DAEDALUS, {"kind": "calibrated", "roll_deg": [5.0, 10.0], "diameter_m": [5.0, 2.5]})
    back = profile_from_dict(tomllib.loads(text), "daedalus")
    assert vpip_section(back)["contact_settings"] == vpip_section(DAEDALUS)["contact_settings"]
    assert vpip_section(back)["gain_sets"] == vpip_section(DAEDALUS)["gain_sets"]
    assert with_settings(back, "paper", "table1").extra["vpip"]["roll_kp"] == 3.0
