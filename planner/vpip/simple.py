"""The baseline rod driver of paper 000 §2 ("simple algorithm"), to compare with the VPIP.

Locomotion (§2.1): a rod the robot has rolled over pushes while it can still reach the ground, i.e.
for ``β < ζ ≤ α``; it is commanded to the ground-contact length and every other rod is retracted.
Eq. 2 (``l = r / cos ζ − r``) is that length for rods that start at the sphere centre; DAEDALUS's rods
start on side discs, so here the contact length is eq. 18 with a flat plane (φ_VPIP = θ_VPIP = 0),
which reduces to eq. 2 when r_s = r_m. ``α`` is the largest ζ at which the rod still reaches the ground
(eq. 1, :attr:`RodParams.push_window_rad`); ``β`` defaults to 1°.

Balancing (§2.2): a two-point controller with a ±3° hysteresis band on the roll error. Outside the
band the rods extend on the side the robot tilts towards and retract on the opposing side; inside it the
last state is kept. Our reading of "extend": the tilted side's rods from straight down to the end of
the push window (0 ≤ ζ ≤ α) are commanded to their ground-contact length (so its pushing rods keep
pushing and the rod under the disc props the shell); "retract": every rod of the other side goes to 0.
(Propping up the front rods as well, ζ in (−α, 0), was tried: in the surrogate it reads as a backward
pitch and the baseline stalls on curves.) Before the first switch both sides only push.
The band is centred on the desired roll (the paper's algorithm only balances upright; centring it
on the desired roll lets the baseline attempt the same path).
"""

from __future__ import annotations

import math

import numpy as np

from planner.vpip.rods import RodCommand, RodParams, rate_limit, rod_lengths


class SimpleDriver:
    """Paper 000 §2 driver with state (balancing side) and rod-speed rate limiting.

    ``balance`` is +1 after a tilt to the left beyond the band (left rods extend, right retract), −1
    after a tilt to the right, 0 before the first switch.
    """

    def __init__(
        self,
        params: RodParams,
        dt_s: float,
        hysteresis_rad: float = math.radians(3.0),
        beta_rad: float = math.radians(1.0),
    ) -> None:
        self.params = params
        self.dt_s = dt_s
        self.hysteresis_rad = hysteresis_rad
        self.beta_rad = beta_rad
        self.alpha_rad = params.push_window_rad
        self.reset()

    def reset(self) -> None:
        self.balance = 0
        self.lengths_m = np.zeros(self.params.n_rods)

    def update_balance(self, roll_rad: float, desired_roll_rad: float) -> int:
        """Two-point controller with hysteresis (§2.2); returns the new balancing state."""
        error = roll_rad - desired_roll_rad
        if error > self.hysteresis_rad:
            self.balance = 1
        elif error < -self.hysteresis_rad:
            self.balance = -1
        return self.balance

    def targets(self, roll_rad: float, pitch_phase_rad: float) -> RodCommand:
        """Target lengths for the current balancing state (before rate limiting)."""
        ground = rod_lengths(self.params, 0.0, 0.0, roll_rad, pitch_phase_rad)
        zeta = ground.zeta_rad
        contact = ground.length_m
        pushing = (zeta > self.beta_rad) & (zeta <= self.alpha_rad)
        bottom = zeta <= self.alpha_rad
        length = np.where(pushing, contact, 0.0)
        if self.balance != 0:
            # paper side factor: left = −1; balance +1 means "tilted left": extend left, retract right
            extend_side = -1.0 if self.balance > 0 else 1.0
            on_extend = ground.side == extend_side
            length = np.where(on_extend & bottom, contact, length)
            length = np.where(~on_extend, 0.0, length)
        return RodCommand(
            zeta,
            ground.side,
            ground.raw_length_m,
            length,
            ground.active,
            np.zeros_like(ground.clamped),
            ground.held,
        )

    def step(self, roll_rad: float, desired_roll_rad: float, pitch_phase_rad: float) -> RodCommand:
        self.update_balance(roll_rad, desired_roll_rad)
        cmd = self.targets(roll_rad, pitch_phase_rad)
        self.lengths_m = rate_limit(cmd.length_m, self.lengths_m, self.params.rod_speed_m_s * self.dt_s)
        return cmd
