"""The maps folder: where the shipped maps live and what is in it (names, kinds, sizes).

The folder is found by :func:`default_maps_dir` (``$SPHEREPLAN_MAPS``, else ``<repo>/maps`` next to the
``planner`` package); :func:`map_files` is the one name → file index the CLI and the service open maps by.
Only the files directly in the folder are indexed and listed. Subfolders are skipped on purpose: ``maps/real``
holds the Nav2 benchmark maps (up to 4 million cells, third-party, Apache-2.0), which are opened by path or
listed with ``sphereplan maps --maps maps/real``, so the service never offers them by name.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import yaml
from PIL import Image, UnidentifiedImageError

from planner.errors import MapError, NotFound
from planner.maps.nav2 import MESH_SUFFIXES, YAML_SUFFIXES

MAPS_ENV = "SPHEREPLAN_MAPS"


def default_maps_dir() -> Path:
    """The folder of shipped maps: ``$SPHEREPLAN_MAPS`` if set, else ``<repo>/maps`` beside ``planner/``.

    The second works for a source checkout or an editable install (the maps are not packaged into
    wheels). Raises :class:`NotFound` (field ``maps``) if the folder does not exist.
    """
    env = os.environ.get(MAPS_ENV)
    folder = Path(env) if env else Path(__file__).resolve().parents[2] / "maps"
    if not folder.is_dir():
        how = f"${MAPS_ENV}" if env else "the repository's maps folder"
        raise NotFound("maps", f"{how} {str(folder)!r} is not a directory")
    return folder


def _image_size(yaml_path: Path) -> tuple[int, int] | None:
    """(width, height) in pixels of a map YAML's image, read from the header only; None if unreadable;
    ValueError if the header declares an image too large for Pillow to decode (a decompression bomb)."""
    try:
        doc = yaml.safe_load(yaml_path.read_text())
        image = Path(str(doc["image"]))
        if not image.is_absolute():
            image = yaml_path.parent / image
        with Image.open(image) as img:
            return int(img.size[0]), int(img.size[1])
    except Image.DecompressionBombError as exc:  # the header says more pixels than Pillow will decode
        raise ValueError(f"image too large to decode ({exc})") from None
    except (OSError, yaml.YAMLError, KeyError, TypeError, UnidentifiedImageError):
        return None


def map_files(folder: str | Path) -> dict[str, Path]:
    """{name: file} of every map in ``folder`` (name = file stem; a YAML grid wins over a mesh of the same
    stem). Only names listed here can be opened by name, so a name can never reach outside the folder."""
    root = Path(folder)
    if not root.is_dir():
        return {}
    order = YAML_SUFFIXES + MESH_SUFFIXES
    out: dict[str, Path] = {}
    for path in sorted((p for p in root.iterdir() if p.suffix.lower() in order and p.is_file()
                        and not p.name.startswith(".")), key=lambda p: (order.index(p.suffix.lower()), p.name)):
        out.setdefault(path.stem, path)
    return out


def _binary_stl_bounds(path: Path) -> Any:
    """(min xyz, max xyz) of a binary STL's vertices read directly (None if it is not a well-formed binary STL).

    A binary STL is an 80-byte header, a little-endian uint32 triangle count and 50 bytes per triangle
    (normal, three vertices as float32 xyz, a uint16); trimesh's bounds are the same vertices' extremes.
    """
    import numpy as np

    data = path.read_bytes()
    if len(data) < 84:
        return None
    count = int.from_bytes(data[80:84], "little")
    if count == 0 or len(data) != 84 + 50 * count:
        return None
    records = np.frombuffer(data, dtype=np.dtype([("n", "<f4", 3), ("v", "<f4", (3, 3)), ("a", "<u2")]),
                            count=count, offset=84)
    vertices = records["v"].reshape(-1, 3).astype(float)
    if not np.isfinite(vertices).all():
        return None
    return vertices.min(axis=0), vertices.max(axis=0)


def list_maps(folder: str | Path | None = None) -> list[dict[str, Any]]:
    """Describe every map in ``folder`` (default :func:`default_maps_dir`), sorted by file name.

    Each entry: ``name`` (file stem), ``file``, ``kind`` (``grid`` for YAML, ``mesh`` for
    .stl/.obj/.ply), ``size_m`` [x, y], ``resolution_m`` (None for meshes) and, for grids sliced from a
    mesh, ``mesh``. Files that cannot be read are listed with ``error`` instead of sizes.
    """
    root = Path(folder) if folder is not None else default_maps_dir()
    if not root.is_dir():
        raise NotFound("maps", f"{str(root)!r} is not a directory")
    entries: list[dict[str, Any]] = []
    for path in sorted(root.iterdir()):
        suffix = path.suffix.lower()
        if suffix in YAML_SUFFIXES:
            entry: dict[str, Any] = {"name": path.stem, "file": path.name, "kind": "grid"}
            try:
                doc = yaml.safe_load(path.read_text())
                resolution = float(doc["resolution"])
                size = _image_size(path)
                if size is None:
                    raise ValueError("image unreadable")
                entry["size_m"] = [round(size[0] * resolution, 6), round(size[1] * resolution, 6)]
                entry["resolution_m"] = resolution
                if doc.get("mesh"):
                    entry["mesh"] = str(doc["mesh"])
            except (OSError, yaml.YAMLError, KeyError, TypeError, ValueError, AttributeError) as exc:
                entry["error"] = f"unreadable map: {exc}"
            entries.append(entry)
        elif suffix in MESH_SUFFIXES:
            entry = {"name": path.stem, "file": path.name, "kind": "mesh", "resolution_m": None}
            try:
                bounds = _binary_stl_bounds(path)
                if bounds is None:  # other formats (and ASCII STL): the mesh loader (trimesh, ~1.5 s to import)
                    from planner.maps.mesh_world import MeshWorld

                    bounds = MeshWorld.from_file(path).mesh.bounds
                (x0, y0, _), (x1, y1, _) = bounds
                entry["size_m"] = [round(float(x1 - x0), 3), round(float(y1 - y0), 3)]
            except MapError as exc:
                entry["error"] = str(exc)
            entries.append(entry)
    return entries
