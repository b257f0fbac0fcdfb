"""Named contact settings and gain sets of a rod-driven profile, applied to its ``[vpip]`` table.

A ``daedalus``-type profile keeps the numbers of each setting in sub-tables of ``[vpip]``::

    [vpip]
    contact = "regolith"              # the setting used when none is asked for
    gains = "rod-rate"
    [vpip.contact_settings.paper]     # ground_friction, rod_tip_friction, ground_torsional_friction_m, ...
    [vpip.gain_sets.table1]           # roll_kp, roll_ki, roll_kd, ..., pitch_integral_limit_deg

:func:`with_settings` returns the profile with the chosen tables' keys written over the top level of
``[vpip]`` (where :class:`~planner.vpip.mujoco_model.BodyParams` and
:func:`~planner.vpip.controllers.gains_from_section` read them) and the chosen names recorded as
``contact`` and ``gains``, so a result says which setting made it. The names a door offers are
:data:`planner.vpip.choices.CONTACTS` and :data:`~planner.vpip.choices.GAIN_SETS`.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from typing import Any

from planner.errors import InvalidInput, RobotProfileError
from planner.robot import RobotProfile
from planner.vpip.choices import CONTACTS, GAIN_SETS

CONTACT_KEYS = frozenset(
    {"ground_friction", "rod_tip_friction", "ground_torsional_friction_m", "ground_rolling_friction_m"}
)
"""What a contact setting may set (:class:`~planner.vpip.mujoco_model.BodyParams` fields)."""

GAIN_KEYS = frozenset(
    {
        "roll_kp",
        "roll_ki",
        "roll_kd",
        "roll_derivative_cutoff_hz",
        "roll_limit_deg",
        "roll_integral_limit_deg",
        "pitch_kp",
        "pitch_ki",
        "pitch_limit_deg",
        "pitch_integral_limit_deg",
    }
)
"""What a gain set may set (:func:`~planner.vpip.controllers.gains_from_section` keys)."""


def _pick(
    section: Mapping[str, Any], kind: str, table: str, names: tuple[str, ...], keys: frozenset[str], name: str | None
) -> tuple[str | None, dict[str, Any]]:
    """The chosen setting's name and keys (``(None, {})`` when the profile has none and none was asked for)."""
    tables = section.get(table)
    if tables is None and name is None:
        return None, {}
    if name is not None and name not in names:
        raise InvalidInput(kind, f"must be one of {', '.join(names)}, got {name!r}")
    if not isinstance(tables, Mapping):
        raise InvalidInput(kind, f"the profile has no [vpip.{table}] tables to choose {name!r} from")
    chosen = name if name is not None else section.get(kind, names[0])
    values = tables.get(chosen)
    if not isinstance(values, Mapping):
        raise RobotProfileError(f"vpip.{table}.{chosen}", "missing: the profile must define this table")
    unknown = sorted(set(values) - keys)
    if unknown:
        allowed = ", ".join(sorted(keys))
        raise RobotProfileError(f"vpip.{table}.{chosen}.{unknown[0]}", f"unknown key (allowed: {allowed})")
    return str(chosen), dict(values)


def with_settings(profile: RobotProfile, contact: str | None = None, gains: str | None = None) -> RobotProfile:
    """The profile with contact setting ``contact`` and gain set ``gains`` applied (None: the profile's own).

    Raises :class:`~planner.errors.InvalidInput` naming ``contact`` or ``gains`` for a name that is not
    offered, and :class:`~planner.errors.RobotProfileError` naming the table when the profile lacks it.
    """
    section = profile.extra.get("vpip")
    if not isinstance(section, Mapping):
        if contact is None and gains is None:
            return profile
        raise InvalidInput("robot", f"profile {profile.name!r} has no [vpip] section (rod-driven robots only)")
    contact_name, contact_keys = _pick(section, "contact", "contact_settings", CONTACTS, CONTACT_KEYS, contact)
    gains_name, gain_keys = _pick(section, "gains", "gain_sets", GAIN_SETS, GAIN_KEYS, gains)
    if contact_name is None and gains_name is None:
        return profile
    merged = {**dict(section), **contact_keys, **gain_keys}
    if contact_name is not None:
        merged["contact"] = contact_name
    if gains_name is not None:
        merged["gains"] = gains_name
    return dataclasses.replace(profile, extra={**dict(profile.extra), "vpip": merged})


def setting_names(profile: RobotProfile) -> dict[str, str | None]:
    """The contact setting and gain set a profile (after :func:`with_settings`) runs with."""
    section = profile.extra.get("vpip")
    if not isinstance(section, Mapping):
        return {"contact": None, "gains": None}
    return {"contact": section.get("contact"), "gains": section.get("gains")}
