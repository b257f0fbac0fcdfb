"""OpenCV, the ``[vision]`` extra, for every module of this folder: a missing install is bad input naming it."""

from __future__ import annotations

from types import ModuleType

from planner.extras import require


def opencv() -> ModuleType:
    """The ``cv2`` module, or :class:`~planner.extras.MissingExtra` naming the ``[vision]`` extra."""
    return require("cv2", "opencv", "stereo perception and image stabilisation (OpenCV)")
