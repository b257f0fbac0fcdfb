"""The ROS map_server codec: read and write YAML + PGM/PNG exactly as nav2_map_server does.

``load_map(path)`` follows ``nav2_map_server/src/map_io.cpp`` (``loadMapYaml`` + ``loadMapFromFile``):

* the YAML must give ``image``, ``resolution``, ``origin``, ``occupied_thresh``, ``free_thresh`` and
  ``negate`` (nav2 requires all six); ``mode`` is optional (``trinary`` by default, or ``scale``/``raw``);
* ``image`` is absolute or relative to the YAML's folder;
* ``origin`` = [x, y, yaw] of the LOWER-LEFT pixel; image row 0 is the TOP, so rows are flipped into
  :class:`~planner.occupancy.OccupancyGrid`'s bottom-up order;
* per pixel, ``shade`` = mean of the R, G, B channels in [0, 1] (grey images: the grey value); in
  trinary mode an alpha channel is averaged in too (nav2 "preserves existing behaviour" this way);
  ``occ = shade`` if ``negate`` else ``1 − shade``;
* trinary: ``occ > occupied_thresh`` → 100, ``occ < free_thresh`` → 0, otherwise −1 (unknown);
* scale: a pixel that is not fully opaque → −1; ``occ > occupied_thresh`` → 100; ``occ < free_thresh``
  → 0; otherwise ``rint((occ − free) / (occupied − free) · 100)``;
* raw: ``round(shade · 255)`` if it lies in 0..100, else −1 (``negate`` and the thresholds are ignored).

The yaw of ``origin`` is kept (in ``grid.origin`` and ``grid.source``) but, as in nav2's costmaps, the
planners treat the grid as axis-aligned: a non-zero yaw is *not* applied to cell coordinates.

``save_map`` writes the YAML and a PGM (PNG with an alpha channel in scale mode, which needs the alpha
for unknown cells) so that ``load_map(save_map(load_map(x)))`` gives back the same data, origin,
resolution and mode. Pixel values follow nav2's ``map_saver`` (254 free, 0 occupied, 205 unknown in
trinary) whenever those decode back to the same cell under the map's thresholds; otherwise the
nearest pixel value that does is used, so a round trip never changes a cell.

"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
import yaml
from PIL import Image, UnidentifiedImageError

from planner.errors import MapError
from planner.occupancy import OCCUPIED, UNKNOWN, OccupancyGrid

MODES = ("trinary", "scale", "raw")
REQUIRED_KEYS = ("image", "resolution", "origin", "occupied_thresh", "free_thresh", "negate")
YAML_SUFFIXES = (".yaml", ".yml")
MESH_SUFFIXES = (".stl", ".obj", ".ply")
# Defaults used when saving a grid that did not come from a YAML (ROS map_saver's classic values;
# with free_thresh 0.196 the conventional unknown grey 205 decodes as unknown).
DEFAULT_OCCUPIED_THRESH = 0.65
DEFAULT_FREE_THRESH = 0.196
# nav2 map_saver's canonical trinary pixels.
_TRINARY_PIXEL = {0: 254, OCCUPIED: 0, UNKNOWN: 205}
_STANDARD_KEYS = {"image", "mode", "resolution", "origin", "negate", "occupied_thresh", "free_thresh"}


# ---------------------------------------------------------------------------------------------- reading


def _read_yaml(path: Path) -> dict[str, Any]:
    if not path.is_file():
        raise MapError("map", f"map file {str(path)!r} does not exist")
    try:
        doc = yaml.safe_load(path.read_text())
    except yaml.YAMLError as exc:
        raise MapError("map", f"{path.name} is not valid YAML: {exc}") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise MapError("map", f"cannot read {path.name}: {exc}") from None
    if not isinstance(doc, dict):
        kind = type(doc).__name__
        raise MapError("map", f"{path.name} must be a YAML mapping of map_server keys, got {kind}")
    missing = [k for k in REQUIRED_KEYS if k not in doc]
    if missing:
        raise MapError(missing[0], f"required key missing from {path.name} (need {', '.join(REQUIRED_KEYS)})")
    return doc


def _number(doc: dict[str, Any], key: str) -> float:
    value = doc[key]
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise MapError(key, f"must be a finite number, got {value!r}")
    return float(value)


def snap_resolution(resolution_m: float) -> float:
    """The resolution (m/cell) a map means: the shortest decimal that rounds to the same float32.

    ``nav_msgs/OccupancyGrid`` carries the resolution as a float32, so 0.05 arrives as 0.05000000074505806;
    planned with as it stands, the grid's cells and the plan differ from the same map read from its YAML.
    Every reader (the YAML codec here, the ROS message readers, inline grids) snaps it, so a resolution within
    float32 rounding of a round value plans exactly as that value does. Only a value that is exactly a float32
    (one that has been through one) is snapped, and by less than float32's half unit in the last place (≤ 3e-8
    relative); any other value is kept as given."""
    value = float(resolution_m)
    if not (math.isfinite(value) and 0 < value < 3e38) or float(np.float32(value)) != value:
        return value
    shortest = float(np.format_float_positional(np.float32(value), unique=True, trim="-"))
    return shortest if np.float32(shortest) == np.float32(value) else value


def _parse_params(doc: dict[str, Any]) -> dict[str, Any]:
    """Validate the map_server keys; returns resolution, origin, thresholds, negate, mode."""
    resolution = _number(doc, "resolution")
    if resolution <= 0:
        raise MapError("resolution", f"must be > 0 m/cell, got {resolution!r}")
    origin = doc["origin"]
    if (
        not isinstance(origin, list | tuple)
        or len(origin) != 3
        or not all(isinstance(v, int | float) and not isinstance(v, bool) for v in origin)
        or not all(math.isfinite(v) for v in origin)
    ):
        raise MapError("origin", f"must be three finite numbers [x, y, yaw], got {origin!r}")
    occupied = _number(doc, "occupied_thresh")
    free = _number(doc, "free_thresh")
    if not 0.0 <= occupied <= 1.0:
        raise MapError("occupied_thresh", f"must lie in [0, 1], got {occupied!r}")
    if not 0.0 <= free <= 1.0:
        raise MapError("free_thresh", f"must lie in [0, 1], got {free!r}")
    if free >= occupied:
        raise MapError("free_thresh", f"must be smaller than occupied_thresh ({free!r} >= {occupied!r})")
    negate = doc["negate"]
    if isinstance(negate, bool):
        negate_flag = negate
    elif isinstance(negate, int) and negate in (0, 1):
        negate_flag = bool(negate)
    else:
        raise MapError("negate", f"must be 0, 1, true or false, got {negate!r}")
    mode = doc.get("mode", "trinary")
    if mode not in MODES:
        raise MapError("mode", f"must be one of {', '.join(MODES)}, got {mode!r}")
    image = doc["image"]
    if not isinstance(image, str) or not image.strip():
        raise MapError("image", f"must be a non-empty file name, got {image!r}")
    return {
        "resolution": snap_resolution(resolution),
        "origin": (float(origin[0]), float(origin[1]), float(origin[2])),
        "occupied_thresh": occupied,
        "free_thresh": free,
        "negate": negate_flag,
        "mode": mode,
        "image": image,
    }


def _read_image(path: Path) -> tuple[np.ndarray, np.ndarray | None]:
    """Read a PGM or PNG; returns (colour (h, w, 1 or 3) in [0, 255], alpha (h, w) in [0, 255] or None).

    A grey image comes back with one channel, which stands for three equal R, G, B channels.
    """
    if not path.is_file():
        raise MapError("image", f"image file {str(path)!r} does not exist")
    try:
        with Image.open(path) as img:
            fmt = img.format
            if fmt == "PPM":
                with path.open("rb") as fh:
                    magic = fh.read(2)
                if magic not in (b"P2", b"P5"):
                    raise MapError("image", f"{path.name} is a PBM/PPM file, not a PGM (magic {magic!r})")
            elif fmt != "PNG":
                raise MapError("image", f"{path.name} must be a PGM or PNG image, got {fmt}")
            img.load()
            mode = img.mode
            if mode in ("I;16", "I;16B", "I"):
                grey = np.asarray(img, dtype=np.float64)
                maxval = 65535.0 if grey.max(initial=0) > 255 or mode.startswith("I;16") else 255.0
                grey = grey * (255.0 / maxval)
                return np.repeat(grey[:, :, None], 3, axis=2), None
            if mode == "L" and "transparency" not in img.info:  # the common case: grey, one channel
                return np.asarray(img, dtype=np.float64)[:, :, None], None
            if mode == "LA":
                la = np.asarray(img, dtype=np.float64)
                return la[:, :, :1], la[:, :, 1]
            has_alpha = mode in ("RGBA", "PA") or "transparency" in img.info
            rgba = np.asarray(img.convert("RGBA" if has_alpha else "RGB"), dtype=np.float64)
    except MapError:
        raise
    except (UnidentifiedImageError, OSError, ValueError) as exc:
        raise MapError("image", f"{path.name} is not a readable PGM or PNG image: {exc}") from None
    if has_alpha:
        return rgba[:, :, :3], rgba[:, :, 3]
    return rgba, None


def decode_pixels(
    rgb: np.ndarray,
    alpha: np.ndarray | None,
    mode: str,
    negate: bool,
    occupied_thresh: float,
    free_thresh: float,
) -> np.ndarray:
    """Turn image pixels (row 0 = top) into occupancy values (row 0 = top) by nav2's rules.

    ``rgb``: (h, w, 3) channel values in [0, 255], or (h, w, 1) for grey (= three equal channels);
    ``alpha``: (h, w) in [0, 255] (255 = opaque) or None. Returns an int8 (h, w) array of 0..100 / −1.
    """
    rgb_sum = rgb[:, :, 0] * 3.0 if rgb.shape[2] == 1 else rgb.sum(axis=2)
    if mode == "trinary" and alpha is not None:
        shade = (rgb_sum + alpha) / (4.0 * 255.0)
    else:
        shade = rgb_sum / (3.0 * 255.0)
    occ = shade if negate else 1.0 - shade
    if mode == "trinary":
        out = np.where(occ > occupied_thresh, OCCUPIED, np.where(occ < free_thresh, 0, UNKNOWN))
    elif mode == "scale":
        between = np.rint((occ - free_thresh) / (occupied_thresh - free_thresh) * 100.0)
        out = np.where(occ > occupied_thresh, OCCUPIED, np.where(occ < free_thresh, 0, between))
        if alpha is not None:
            out = np.where(alpha < 255, UNKNOWN, out)
    else:  # raw; std::round rounds halves away from zero, which floor(x + 0.5) matches for x >= 0
        percent = np.floor(shade * 255.0 + 0.5)
        out = np.where((percent >= 0) & (percent <= 100), percent, UNKNOWN)
    return out.astype(np.int8)


def _blocking_threshold(mode: str, occupied_thresh: float) -> int:
    """``OccupancyGrid.occupied_threshold`` for a loaded map (percent; ``data >= it`` blocks).

    trinary: cells are 0/100/−1, so 65 is as good as any value in 1..100. scale: only cells beyond
    ``occupied_thresh`` (stored as 100) are lethal, like nav2's static layer (lethal_threshold 100).
    raw: values are occupancy percent; a cell blocks when it is above ``occupied_thresh`` (strict, as
    in the trinary rule).
    """
    if mode == "scale":
        return OCCUPIED
    if mode == "raw":
        return min(OCCUPIED, math.floor(occupied_thresh * 100.0 + 1e-9) + 1)
    return 65


def load_map(path: str | Path) -> OccupancyGrid:
    """Load a ROS map_server map (YAML + PGM/PNG) as nav2_map_server does.

    Returns an :class:`OccupancyGrid` named after the YAML's stem, with the YAML fields (plus
    ``yaml_path``) in ``grid.source``. Raises :class:`MapError` naming the bad field.
    """
    yaml_path = Path(path)
    if yaml_path.suffix.lower() not in YAML_SUFFIXES and yaml_path.suffix.lower() in MESH_SUFFIXES:
        raise MapError("map", f"{yaml_path.name} is a mesh; use load_any() or planner.maps.mesh_world")
    doc = _read_yaml(yaml_path)
    params = _parse_params(doc)
    image_path = Path(params["image"])
    if not image_path.is_absolute():
        image_path = yaml_path.parent / image_path
    rgb, alpha = _read_image(image_path)
    top_down = decode_pixels(
        rgb, alpha, params["mode"], params["negate"], params["occupied_thresh"], params["free_thresh"]
    )
    source = dict(doc)
    source["mode"] = params["mode"]
    source["yaml_path"] = str(yaml_path)
    mesh = doc.get("mesh")
    return OccupancyGrid(
        data=np.ascontiguousarray(top_down[::-1]),
        resolution_m=params["resolution"],
        origin=params["origin"],
        occupied_threshold=_blocking_threshold(params["mode"], params["occupied_thresh"]),
        name=yaml_path.stem,
        source=source,
        mesh_path=(yaml_path.parent / str(mesh)).resolve() if mesh else None,
    )


# ---------------------------------------------------------------------------------------------- writing


def _trinary_class(data: np.ndarray, occupied_thresh: float, free_thresh: float) -> np.ndarray:
    """nav2 map_saver's trinary classes of cell values (0, 100 or −1)."""
    free_int = int(np.rint(free_thresh * 100.0))
    occ_int = int(np.rint(occupied_thresh * 100.0))
    unknown = (data < 0) | (data > 100)
    known = np.where(data <= free_int, 0, np.where(data >= occ_int, OCCUPIED, UNKNOWN))
    return np.where(unknown, UNKNOWN, known)


def _pixel_for_values(
    values: np.ndarray, mode: str, occupied_thresh: float, free_thresh: float
) -> dict[int, int]:
    """For every cell value present, an 8-bit grey pixel that decodes back to it (negate = 0, opaque)."""
    grey = np.arange(256, dtype=np.float64)
    decoded = decode_pixels(np.repeat(grey[None, :, None], 3, axis=2), None, mode, False,
                            occupied_thresh, free_thresh)[0]
    table: dict[int, int] = {}
    for value in np.unique(values).tolist():
        if mode == "trinary":
            preferred = _TRINARY_PIXEL[value]
        elif mode == "scale":
            preferred = round(255.0 * (100 - value) / 100.0)
        else:
            preferred = value
        candidates = np.flatnonzero(decoded == value)
        if candidates.size == 0:
            field = "free_thresh" if value not in (0, OCCUPIED) else "occupied_thresh"
            raise MapError(
                field,
                f"no 8-bit pixel decodes to cell value {value} in {mode} mode with thresholds "
                f"free={free_thresh}, occupied={occupied_thresh}; widen the band between them",
            )
        table[value] = int(candidates[np.argmin(np.abs(candidates - preferred))])
    return table


def _yaml_scalar(value: Any) -> str:
    return yaml.safe_dump(value, default_flow_style=True, width=10_000).strip().removesuffix("...").strip()


def save_map(grid: OccupancyGrid, yaml_path: str | Path, image_name: str | None = None) -> Path:
    """Write ``grid`` as a map_server YAML plus image next to it; returns the YAML path.

    Mode and thresholds come from ``grid.source`` (defaults: trinary, 0.65 / 0.196); ``negate`` is
    written as 0 (like nav2's map_saver). The image is a binary PGM (P5), or a grey+alpha PNG in scale
    mode (unknown cells transparent). Extra YAML keys kept in ``grid.source`` (e.g. ``mesh``) are
    written after the standard ones. The output is byte-deterministic.
    """
    yaml_path = Path(yaml_path)
    src = grid.source
    mode = src.get("mode", "trinary")
    if mode not in MODES:
        raise MapError("mode", f"must be one of {', '.join(MODES)}, got {mode!r}")
    occupied_thresh = float(src.get("occupied_thresh", DEFAULT_OCCUPIED_THRESH))
    free_thresh = float(src.get("free_thresh", DEFAULT_FREE_THRESH))
    if not 0.0 <= free_thresh < occupied_thresh <= 1.0:
        raise MapError("free_thresh", f"need 0 <= free_thresh < occupied_thresh <= 1, got {free_thresh}, "
                                      f"{occupied_thresh}")
    if image_name is None:
        image_name = yaml_path.stem + (".png" if mode == "scale" else ".pgm")
    if Path(image_name).suffix.lower() not in (".pgm", ".png"):
        raise MapError("image", f"must end in .pgm or .png, got {image_name!r}")
    if mode == "scale" and not image_name.lower().endswith(".png"):
        raise MapError("image", "scale mode needs a PNG (unknown cells are stored as transparent pixels)")

    top_down = grid.data[::-1].astype(np.int16)
    if mode == "trinary":
        values = _trinary_class(top_down, occupied_thresh, free_thresh)
    else:
        values = np.where((top_down < 0) | (top_down > 100), UNKNOWN, top_down)
    known = values[values != UNKNOWN] if mode == "scale" else values
    table = _pixel_for_values(known, mode, occupied_thresh, free_thresh)
    if mode == "raw":
        table[UNKNOWN] = 255
    lut = np.zeros(256, dtype=np.uint8)  # index value + 1 (so −1 → 0)
    for value, pixel in table.items():
        lut[value + 1] = pixel
    grey = lut[values + 1]
    image_path = yaml_path.parent / image_name
    yaml_path.parent.mkdir(parents=True, exist_ok=True)
    if mode == "scale":
        alpha = np.where(values == UNKNOWN, 0, 255).astype(np.uint8)
        grey = np.where(values == UNKNOWN, 128, grey).astype(np.uint8)
        grey_alpha = np.stack([grey, alpha], axis=2)
        Image.fromarray(grey_alpha, mode="LA").save(image_path, format="PNG", optimize=False)
    elif image_name.lower().endswith(".png"):
        Image.fromarray(grey, mode="L").save(image_path, format="PNG", optimize=False)
    else:
        Image.fromarray(grey, mode="L").save(image_path, format="PPM")

    lines = [
        f"image: {_yaml_scalar(image_name)}",
        f"mode: {mode}",
        f"resolution: {grid.resolution_m!r}",
        f"origin: [{', '.join(repr(float(v)) for v in grid.origin)}]",
        "negate: 0",
        f"occupied_thresh: {occupied_thresh!r}",
        f"free_thresh: {free_thresh!r}",
    ]
    for key, value in src.items():
        if key not in _STANDARD_KEYS and key != "yaml_path":
            lines.append(f"{_yaml_scalar(key)}: {_yaml_scalar(value)}")
    yaml_path.write_text("\n".join(lines) + "\n")
    return yaml_path
