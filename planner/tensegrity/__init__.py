"""TeXploR, the two curved-link tensegrity robot of paper 002: statics, rolling gaits and form finding.

Public surface (what the service layer calls; each returns exactly the JSON the CLI prints):

* :func:`static_equilibria` — the four hybrid states at given slider angles (closed form, checked
  against a direct potential-energy minimisation).
* :func:`plan_gait` — slider trajectories θ1(t), θ2(t) that roll the robot a distance, with states,
  contact angles, ground contacts and body pose per step.
* :func:`form_find` — cable-energy form finding (eq. 18): T12 and the cable lengths.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from planner.tensegrity.formfinding import form_find
    from planner.tensegrity.gait import ALLOWED_TRANSITIONS, plan_gait
    from planner.tensegrity.statics import static_equilibria

#: public name → its module, imported on first use (``tensegrity static`` must not pay for the others)
_EXPORTS = {
    "ALLOWED_TRANSITIONS": "planner.tensegrity.gait",
    "form_find": "planner.tensegrity.formfinding",
    "plan_gait": "planner.tensegrity.gait",
    "static_equilibria": "planner.tensegrity.statics",
}


def __getattr__(name: str) -> Any:
    if name in _EXPORTS:
        return getattr(importlib.import_module(_EXPORTS[name]), name)
    raise AttributeError(f"module 'planner.tensegrity' has no attribute {name!r}")


__all__ = ["ALLOWED_TRANSITIONS", "form_find", "plan_gait", "static_equilibria"]
