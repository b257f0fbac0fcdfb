"""VPIP for rod-driven spheres (paper 000): rod driver (eq. 4–18), angle controllers, curvature cascade.

Public surface: the report functions the CLI and services call, plus the building blocks. Names are
imported on first use (as in :mod:`planner`), so ``import planner.vpip.choices`` — what the command line's
``--help`` needs — loads neither numpy nor MuJoCo.
"""

from __future__ import annotations

from planner.lazy import lazy_exports

#: public name → the module that defines it
_EXPORTS: dict[str, str] = {
    "calibrate_report": "planner.vpip.api",
    "parse_runs_csv": "planner.vpip.api",
    "profile_toml": "planner.vpip.api",
    "radius_report": "planner.vpip.api",
    "rods_report": "planner.vpip.api",
    "roll_report": "planner.vpip.api",
    "schedule_report": "planner.vpip.api",
    "PathReference": "planner.vpip.cascade",
    "SurrogatePlant": "planner.vpip.cascade",
    "rod_params": "planner.vpip.cascade",
    "run_schedule": "planner.vpip.cascade",
    "PID": "planner.vpip.controllers",
    "PIDGains": "planner.vpip.controllers",
    "PitchController": "planner.vpip.controllers",
    "RollController": "planner.vpip.controllers",
    "RodCommand": "planner.vpip.rods",
    "RodDriver": "planner.vpip.rods",
    "RodParams": "planner.vpip.rods",
    "equivalent_plane": "planner.vpip.rods",
    "rod_lengths": "planner.vpip.rods",
    "with_settings": "planner.vpip.settings",
    "SimpleDriver": "planner.vpip.simple",
}

__all__ = sorted(_EXPORTS)


__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS, globals(), __all__)
