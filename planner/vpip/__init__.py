"""VPIP for rod-driven spheres (paper 000): rod driver (eq. 4–18), angle controllers, curvature cascade.

Public surface: the report functions the CLI and services call, plus the building blocks.
"""

from planner.vpip.api import (
    calibrate_report,
    parse_runs_csv,
    profile_toml,
    radius_report,
    rods_report,
    roll_report,
    schedule_report,
)
from planner.vpip.cascade import PathReference, SurrogatePlant, rod_params, run_schedule
from planner.vpip.controllers import PID, PIDGains, PitchController, RollController
from planner.vpip.rods import RodCommand, RodDriver, RodParams, equivalent_plane, rod_lengths
from planner.vpip.simple import SimpleDriver

__all__ = [
    "PID",
    "PIDGains",
    "PathReference",
    "PitchController",
    "RodCommand",
    "RodDriver",
    "RodParams",
    "RollController",
    "SimpleDriver",
    "SurrogatePlant",
    "calibrate_report",
    "equivalent_plane",
    "parse_runs_csv",
    "profile_toml",
    "radius_report",
    "rod_lengths",
    "rod_params",
    "rods_report",
    "roll_report",
    "run_schedule",
    "schedule_report",
]
