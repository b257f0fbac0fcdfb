"""The names a VPIP run is configured by: plants, rod drivers, contact settings and gain sets.

The doors offer these as choices (``sphereplan vpip circle --plant/--driver/--contact/--gains``), so they
live here, in a module that imports nothing heavy: building the command line's ``--help`` must not load
numpy or MuJoCo. The planner's modules take the same names from here; a profile's ``[vpip]`` table holds
the numbers behind each contact setting and gain set (:mod:`planner.vpip.settings`).
"""

from __future__ import annotations

DRIVERS = ("vpip", "simple")
"""Rod drivers: the VPIP (eq. 18, paper 000 §4) or the §2 simple baseline."""

PLANTS = ("surrogate", "mujoco")
"""Plants the cascade drives: the fast surrogate (turns by the profile's roll table) or MuJoCo rod physics."""

CONTACTS = ("regolith", "paper")
"""Contact settings of the MuJoCo model (``[vpip.contact_settings.<name>]``); the first is the default."""

GAIN_SETS = ("rod-rate", "table1")
"""Controller gain sets (``[vpip.gain_sets.<name>]``); the first is the default, ``table1`` is paper 000's."""
