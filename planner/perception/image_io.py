"""Reading and writing image files for the perception verbs (OpenCV's codecs: PNG, JPEG, BMP, TIFF, ...)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from planner.errors import InvalidInput


def read_image(path: str | Path, field: str) -> np.ndarray:
    """An image file as an array (grey (H, W) or BGR (H, W, 3), as stored); unreadable → InvalidInput(field)."""
    import cv2

    p = Path(path)
    if not p.is_file():
        raise InvalidInput(field, f"file {p} does not exist")
    image = cv2.imread(str(p), cv2.IMREAD_UNCHANGED)
    if image is None:
        raise InvalidInput(field, f"{p} is not a readable image")
    if image.ndim == 3 and image.shape[2] == 4:
        image = image[:, :, :3]
    return np.asarray(image)


def write_image(path: str | Path, image: np.ndarray, field: str) -> None:
    """Write ``image`` (format from the extension); a refusal is InvalidInput(field)."""
    import cv2

    try:
        ok = cv2.imwrite(str(path), image)
    except cv2.error as exc:
        raise InvalidInput(field, f"cannot write {path}: {str(exc).strip().splitlines()[-1]}") from None
    if not ok:
        raise InvalidInput(field, f"cannot write {path}")
