"""The optional parts of the install and how a command asks for one (pyproject.toml's extras).

The core install plans, simulates (pure-pursuit tracker) and serves. The heavy parts are extras: ``[physics]``
(MuJoCo, the DAEDALUS rod plant), ``[control]`` (CasADi: the MPC tracker and the pendulum controllers' QP
solvers), ``[mesh]`` (trimesh and python-fcl: mesh maps, .stl/.obj/.ply), ``[vision]`` (OpenCV: stereo perception
and image stabilisation) and ``[dev]`` (all four, plus the test tools). Code that needs an extra imports its
module through :func:`require`, so a missing extra is bad input naming the extra to install (CLI exit 2,
HTTP 422, a Zenoh error reply), never an ``ImportError`` traceback.
"""

from __future__ import annotations

import importlib
from types import ModuleType

from planner.errors import InvalidInput

#: module → the extra that installs it
EXTRA_OF = {"casadi": "control", "mujoco": "physics", "fcl": "mesh", "trimesh": "mesh", "cv2": "vision"}


class MissingExtra(InvalidInput):
    """A command needs a part of sphereplan that is not installed; ``extra`` names the extra to install."""

    def __init__(self, field: str, extra: str, what: str) -> None:
        super().__init__(field, f"{what} needs the [{extra}] extra: pip install 'sphereplan[{extra}]' "
                                f"(from a clone: pip install -e '.[{extra}]')")
        self.extra = extra


def require(module: str, field: str, what: str) -> ModuleType:
    """Import ``module`` (a key of :data:`EXTRA_OF`) or raise :class:`MissingExtra` naming ``field`` (the
    option or request field that asked for it) and what needs it."""
    try:
        return importlib.import_module(module)
    except ImportError:
        raise MissingExtra(field, EXTRA_OF[module], what) from None
