"""MJCF model of the rod-driven DAEDALUS sphere (paper 000 §4, Table 1, Figs. 1 and 6), built from the profile.

Paper 000 evaluates the VPIP in a Gazebo model of DAEDALUS: a 0.232 m shell, two side discs with eight
telescopic rods each (Table 1: l_max = 0.21 m, extension speed 0.1 m/s, 1.4 kg per rod), a 15 kg
baseplate and a 7 kg battery that hangs as a pendulum (§5, discussion of Fig. 8). This module writes the
same robot as a MuJoCo model, with the rod geometry of eq. 5–12 so that the rod driver's eq. 18 lengths
put the simulated rod tips on the VPIP (tested against eq. 4 in ``tests/planner/vpip/test_vpip_mujoco.py``).

Body frame (at the sphere centre) = the paper's frame of eq. 9/12 at zero roll and zero pitch phase:
``x`` to the right (from the left disc to the right disc, the axle), ``y`` forward (rolling direction),
``z`` up. Side disc centres at ``(s_f·d_m^s, 0, 0)`` (eq. 7/9, s_f = −1 left, +1 right); rod ``k`` of a
ring points along ``(0, −sin ζ_k, −cos ζ_k)`` with ``ζ_k = 2πk/n`` (eq. 12 at φ_r = 0), the same layout
as :func:`planner.vpip.rods.rod_layout` (rods ``0 … n−1`` left, ``n … 2n−1`` right). Each rod is a
housing welded to the body (the fixed part, from the disc centre to the shell) and a telescope on a
slide joint along the rod axis, range ``[0, l_max]``, driven by a velocity servo (a leadscrew: the
plant in :mod:`planner.vpip.mujoco_plant` commands a velocity within ``±rod_speed_m_s``, so no rod ever
moves faster than Table 1's 0.1 m/s). The servo has no force limit: a telescope on a self-locking
leadscrew holds whatever the ground pushes on it (a force-limited servo let landing impacts drive the
rods back at up to 3 m/s, far beyond any real rod). The rod line ends at
``λ = r_s + l`` from the disc centre (site ``tip_k``); the rod's contact geom is a small sphere whose
outermost point is that tip, so a retracted rod is flush with the shell (eq. 7: r_s² + d_m^s² = r_m²).

Only the shell and the rod tips touch the floor; nothing touches anything else (the rods push the ground
through the shell as on the real robot: their housings are part of the shell body).

Physical numbers come from the profile's ``[vpip]`` table (``planner/robots/daedalus.toml`` says where
each comes from); :class:`BodyParams` lists them with their defaults.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, fields
from typing import Any

from planner.errors import RobotProfileError
from planner.vpip.rods import RodParams


@dataclass(frozen=True)
class BodyParams:
    """Masses, inertias, contact and servo parameters of the MuJoCo model (SI units).

    Table 1 of paper 000: ``shell_mass_kg`` 3, ``shell_inertia_kg_m2`` 0.108 (2/3·m·r², a thin shell),
    ``baseplate_mass_kg`` 15, ``battery_mass_kg`` 7, ``rod_mass_kg`` 1.4. The rest are assumptions
    (documented in the profile and docs/vpip.md).
    """

    shell_mass_kg: float = 3.0
    shell_inertia_kg_m2: float = 0.108
    baseplate_mass_kg: float = 15.0
    baseplate_radius_m: float = 0.15
    baseplate_thickness_m: float = 0.06
    battery_mass_kg: float = 7.0
    battery_arm_m: float = 0.08
    battery_damping_n_m_s: float = 0.5
    rod_mass_kg: float = 1.4
    rod_moving_fraction: float = 0.5
    rod_tip_radius_m: float = 0.01
    rod_servo_gain_n_s_m: float = 1.0e4
    rod_servo_tracking_s: float = 0.02
    ground_friction: float = 1.0
    rod_tip_friction: float = 1.0
    ground_torsional_friction_m: float = 0.03
    ground_rolling_friction_m: float = 0.0
    timestep_s: float = 0.001

    @classmethod
    def from_section(cls, section: Mapping[str, Any]) -> BodyParams:
        """Read the ``[vpip]`` keys named like the fields (missing keys keep the defaults)."""
        kwargs: dict[str, float] = {}
        for f in fields(cls):
            if f.name in section:
                value = section[f.name]
                if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
                    raise RobotProfileError(f"vpip.{f.name}", f"must be a finite number, got {value!r}")
                kwargs[f.name] = float(value)
        out = cls(**kwargs)
        for f in fields(cls):
            value = getattr(out, f.name)
            zero_ok = f.name in ("ground_rolling_friction_m", "ground_torsional_friction_m", "battery_damping_n_m_s")
            if value < 0 or (value == 0 and not zero_ok):
                raise RobotProfileError(f"vpip.{f.name}", f"must be > 0, got {value!r}")
        if out.rod_moving_fraction > 1:
            raise RobotProfileError("vpip.rod_moving_fraction", f"must be in (0, 1], got {out.rod_moving_fraction}")
        if out.timestep_s > 0.005:
            raise RobotProfileError("vpip.timestep_s", f"must be <= 0.005 s, got {out.timestep_s}")
        return out

    @property
    def total_mass_kg(self) -> float:
        return self.shell_mass_kg + self.baseplate_mass_kg + self.battery_mass_kg

    def to_json(self) -> dict[str, float]:
        return {f.name: getattr(self, f.name) for f in fields(self)}


def _v(values: tuple[float, ...] | list[float]) -> str:
    return " ".join(f"{float(x):.9g}" for x in values)


def rod_axes(params: RodParams) -> list[tuple[tuple[float, float, float], tuple[float, float, float]]]:
    """(disc centre, unit rod direction) of every rod in the body frame (eq. 9/12 at φ_r = 0, phase 0)."""
    n = params.rods_per_side
    out = []
    for side in (-1.0, 1.0):
        for k in range(n):
            zeta = 2.0 * math.pi * k / n
            out.append(((side * params.d_m_s, 0.0, 0.0), (0.0, -math.sin(zeta), -math.cos(zeta))))
    return out


def build_mjcf(params: RodParams, body: BodyParams) -> str:
    """The MJCF text of the robot on a flat floor (see the module doc)."""
    r_m, r_s, l_max = params.r_m, params.r_s, params.l_max
    rod_fixed = body.rod_mass_kg * (1.0 - body.rod_moving_fraction)
    rod_moving = body.rod_mass_kg * body.rod_moving_fraction
    kv = body.rod_servo_gain_n_s_m
    seg = l_max / 3.0  # Table 1: three telescopic segments
    # baseplate: a solid disc around the axle (x); battery: a compact box on a pendulum arm
    bp_m, bp_r, bp_h = body.baseplate_mass_kg, body.baseplate_radius_m, body.baseplate_thickness_m
    bp_inertia = (0.5 * bp_m * bp_r**2, 0.25 * bp_m * bp_r**2 + bp_m * bp_h**2 / 12.0)
    bat_i = body.battery_mass_kg * (0.1**2 + 0.06**2) / 12.0
    shell_i = body.shell_inertia_kg_m2
    friction = _v((body.ground_friction, body.ground_torsional_friction_m, body.ground_rolling_friction_m))
    tip_friction = _v((body.rod_tip_friction, 0.0, 0.0))
    lines = [
        '<mujoco model="daedalus-vpip">',
        '  <compiler angle="radian" autolimits="true"/>',
        f'  <option timestep="{body.timestep_s:.9g}" integrator="implicitfast" cone="elliptic" gravity="0 0 -9.81"/>',
        "  <worldbody>",
        f'    <geom name="floor" type="plane" size="0 0 0.05" contype="1" conaffinity="1" condim="6" '
        f'friction="{friction}"/>',
        f'    <body name="sphere" pos="0 0 {r_m:.9g}">',
        '      <freejoint name="root"/>',
        f'      <inertial pos="0 0 0" mass="{body.shell_mass_kg:.9g}" diaginertia="{_v((shell_i,) * 3)}"/>',
        f'      <geom name="shell" type="sphere" size="{r_m:.9g}" contype="2" conaffinity="1" condim="6" priority="1" '
        f'friction="{friction}" mass="0"/>',
        '      <body name="baseplate">',
        f'        <inertial pos="0 0 0" mass="{bp_m:.9g}" '
        f'diaginertia="{_v((bp_inertia[0], bp_inertia[1], bp_inertia[1]))}"/>',
        "      </body>",
        '      <body name="battery">',
        f'        <joint name="battery" type="hinge" axis="1 0 0" damping="{body.battery_damping_n_m_s:.9g}"/>',
        f'        <inertial pos="0 0 {-body.battery_arm_m:.9g}" mass="{body.battery_mass_kg:.9g}" '
        f'diaginertia="{_v((bat_i,) * 3)}"/>',
        "      </body>",
    ]
    tip_r = body.rod_tip_radius_m
    for i, (centre, direction) in enumerate(rod_axes(params)):
        # housing frame: origin at the disc centre, z along the rod
        lines += [
            f'      <body name="housing{i}" pos="{_v(centre)}" zaxis="{_v(direction)}">',
            f'        <inertial pos="0 0 {0.5 * r_s:.9g}" mass="{rod_fixed:.9g}" '
            f'diaginertia="{_v((rod_fixed * r_s**2 / 12.0,) * 2 + (1e-5,))}"/>',
            f'        <body name="rod{i}">',
            f'          <joint name="rod{i}" type="slide" axis="0 0 1" range="0 {l_max:.9g}"/>',
            f'          <inertial pos="0 0 {r_s - 0.5 * seg:.9g}" mass="{rod_moving:.9g}" '
            f'diaginertia="{_v((rod_moving * seg**2 / 12.0,) * 2 + (1e-5,))}"/>',
            f'          <geom name="tip{i}" type="sphere" pos="0 0 {r_s - tip_r:.9g}" size="{tip_r:.9g}" '
            f'contype="2" conaffinity="1" condim="3" priority="1" friction="{tip_friction}" mass="0"/>',
            f'          <site name="tip{i}" pos="0 0 {r_s:.9g}" size="0.005"/>',
            "        </body>",
            "      </body>",
        ]
    lines += ["    </body>", "  </worldbody>", "  <actuator>"]
    for i in range(params.n_rods):
        lines.append(
            f'    <velocity name="rod{i}" joint="rod{i}" kv="{kv:.9g}" '
            f'ctrlrange="{-params.rod_speed_m_s:.9g} {params.rod_speed_m_s:.9g}"/>'
        )
    lines += ["  </actuator>", "</mujoco>", ""]
    return "\n".join(lines)
