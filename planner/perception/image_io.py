"""Reading and writing image files for the perception verbs (OpenCV's codecs: PNG, JPEG, BMP, TIFF, ...)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from planner.errors import InvalidInput
from planner.perception.opencv import opencv


def read_image(path: str | Path, field: str) -> np.ndarray:
    """An image file as an array (grey (H, W) or BGR (H, W, 3), as stored); unreadable → InvalidInput(field)."""
    cv2 = opencv()

    p = Path(path)
    if not p.is_file():
        raise InvalidInput(field, f"file {p} does not exist")
    image = cv2.imread(str(p), cv2.IMREAD_UNCHANGED)
    if image is None:
        raise InvalidInput(field, f"{p} is not a readable image")
    if image.ndim == 3 and image.shape[2] == 4:
        image = image[:, :, :3]
    return np.asarray(image)


def decode_image(data: bytes, field: str, max_pixels: int = 16_000_000) -> np.ndarray:
    """An image file's bytes (PNG, JPEG, ...) as an array, grey or BGR as stored; undecodable → InvalidInput.
    The size is read from the header first: more than ``max_pixels`` pixels is refused before decoding (a small
    compressed file can hold a huge picture)."""
    import io

    cv2 = opencv()
    from PIL import Image, UnidentifiedImageError

    try:
        with Image.open(io.BytesIO(data)) as header:
            width, height = header.size
    except (UnidentifiedImageError, OSError, ValueError, Image.DecompressionBombError):
        raise InvalidInput(field, "is not a readable image file (PNG, JPEG, ...)") from None
    if width * height > max_pixels:
        raise InvalidInput(field, f"is {width} × {height} px; at most {max_pixels} pixels are accepted")
    image = cv2.imdecode(np.frombuffer(data, dtype=np.uint8), cv2.IMREAD_UNCHANGED) if data else None
    if image is None:
        raise InvalidInput(field, "is not a readable image file (PNG, JPEG, ...)")
    return np.asarray(image[:, :, :3] if image.ndim == 3 and image.shape[2] == 4 else image)


def write_image(path: str | Path, image: np.ndarray, field: str) -> None:
    """Write ``image`` (format from the extension); a refusal is InvalidInput(field)."""
    cv2 = opencv()

    try:
        ok = cv2.imwrite(str(path), image)
    except cv2.error as exc:
        raise InvalidInput(field, f"cannot write {path}: {str(exc).strip().splitlines()[-1]}") from None
    if not ok:
        raise InvalidInput(field, f"cannot write {path}")
