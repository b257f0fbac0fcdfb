"""map_server YAML + PGM/PNG loading follows every nav2_map_server rule; saving round-trips."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from planner.errors import MapError
from planner.maps.nav2 import decode_pixels, load_map, save_map
from planner.occupancy import OccupancyGrid

YAML_TEMPLATE = (
    "image: {image}\nresolution: {resolution}\norigin: {origin}\nnegate: {negate}\n"
    "occupied_thresh: {occ}\nfree_thresh: {free}\n{extra}"
)


def write_map(
    tmp_path: Path,
    pixels: np.ndarray,
    *,
    image: str = "m.pgm",
    resolution: object = 0.5,
    origin: object = "[1.0, -2.0, 0.0]",
    negate: object = 0,
    occ: object = 0.65,
    free: object = 0.196,
    extra: str = "",
    mode_img: str | None = None,
) -> Path:
    """Write a YAML + image (pixels given top row first, as the image stores them)."""
    img_path = tmp_path / image
    if mode_img is None:
        mode_img = "L" if pixels.ndim == 2 else ("LA" if pixels.shape[2] == 2 else "RGBA")
    fmt = "PNG" if image.endswith(".png") else "PPM"
    Image.fromarray(pixels.astype(np.uint8), mode=mode_img).save(img_path, format=fmt)
    yaml_path = tmp_path / "m.yaml"
    yaml_path.write_text(
        YAML_TEMPLATE.format(
            image=image, resolution=resolution, origin=origin, negate=negate, occ=occ, free=free, extra=extra
        )
    )
    return yaml_path


# An image 3 rows x 4 columns; row 0 is the top of the map.
PIXELS = np.array(
    [
        [0, 254, 205, 254],
        [254, 254, 254, 254],
        [254, 100, 200, 0],
    ],
    dtype=np.uint8,
)


def test_origin_is_lower_left_and_rows_flip(tmp_path: Path) -> None:
    grid = load_map(write_map(tmp_path, PIXELS))
    assert grid.width == 4 and grid.height == 3
    assert grid.origin == (1.0, -2.0, 0.0)
    assert grid.resolution_m == 0.5
    # The image's top-left black pixel is the grid's top row (iy = 2), column 0.
    assert grid.data[2, 0] == 100
    # The image's bottom-right black pixel is cell (0, 0)... column 3 of row 0.
    assert grid.data[0, 3] == 100
    # World point just inside the lower-left corner maps to cell (0, 0), whose pixel is image row 2, col 0.
    assert grid.world_to_cell(1.01, -1.99) == (0, 0)
    assert grid.data[0, 0] == 0
    # Top-right region of the image (row 0, col 3) is free; (row 0, col 2) = 205 → unknown.
    assert grid.data[2, 2] == -1
    assert grid.name == "m"
    assert grid.source["image"] == "m.pgm"
    assert grid.source["mode"] == "trinary"


def test_trinary_thresholds_are_strict(tmp_path: Path) -> None:
    # occ = (255 - p) / 255. With occ_th = 0.6 and free_th = 0.2:
    # p = 102 → occ = 0.6 exactly → not > 0.6 → unknown; p = 101 → occ > 0.6 → occupied.
    # p = 203 → occ = 0.2039 → not < 0.2 → unknown; p = 205 → occ = 0.196 < 0.2 → free.
    px = np.array([[102, 101, 203, 205]], dtype=np.uint8)
    grid = load_map(write_map(tmp_path, px, occ=0.6, free=0.2))
    assert grid.data[0].tolist() == [-1, 100, -1, 0]


def test_negate_swaps_black_and_white(tmp_path: Path) -> None:
    px = np.array([[0, 255, 205]], dtype=np.uint8)
    plain = load_map(write_map(tmp_path, px, negate=0))
    assert plain.data[0].tolist() == [100, 0, -1]
    negated = load_map(write_map(tmp_path, px, negate=1))
    # occ = p / 255: 0 → free, 255 → occupied, 205 → 0.804 > 0.65 → occupied.
    assert negated.data[0].tolist() == [0, 100, 100]
    assert load_map(write_map(tmp_path, px, negate="true")).data[0].tolist() == [0, 100, 100]


def test_scale_mode_maps_band_linearly(tmp_path: Path) -> None:
    # occ_th = 0.8, free_th = 0.2 → p with occ = 0.5 is in the middle of the band: 50.
    p_mid = 255 - round(0.5 * 255)  # 127 → occ = 128/255 = 0.50196
    px = np.array([[0, 255, p_mid, 250]], dtype=np.uint8)
    grid = load_map(write_map(tmp_path, px, occ=0.8, free=0.2, extra="mode: scale\n"))
    expected_mid = int(np.rint((128 / 255 - 0.2) / 0.6 * 100))
    assert grid.data[0].tolist() == [100, 0, expected_mid, 0]
    assert grid.source["mode"] == "scale"
    # Only lethal cells block in scale mode (nav2 static layer: lethal_threshold 100).
    assert grid.blocked().tolist() == [[True, False, False, False]]


def test_scale_mode_transparent_pixel_is_unknown(tmp_path: Path) -> None:
    px = np.array([[[255, 255], [255, 254], [0, 255]]], dtype=np.uint8)  # grey + alpha
    grid = load_map(write_map(tmp_path, px, image="m.png", extra="mode: scale\n"))
    assert grid.data[0].tolist() == [0, -1, 100]


def test_trinary_averages_alpha_in(tmp_path: Path) -> None:
    # White but fully transparent: shade = (255*3 + 0) / (4*255) = 0.75 → occ 0.25 → between → unknown
    # with free_th 0.196; opaque white → free.
    px = np.array([[[255, 255, 255, 0], [255, 255, 255, 255]]], dtype=np.uint8)
    grid = load_map(write_map(tmp_path, px, image="m.png"))
    assert grid.data[0].tolist() == [-1, 0]


def test_trinary_grey_alpha_counts_grey_three_times(tmp_path: Path) -> None:
    # nav2 sees a grey+alpha pixel as R = G = B = grey plus alpha: shade = (3 g + a) / (4 · 255).
    # g = 255, a = 0 → 0.75 → occ 0.25 → unknown; g = 0, a = 255 → 0.25 → occ 0.75 → occupied.
    px = np.array([[[255, 0], [0, 255], [255, 255]]], dtype=np.uint8)
    grid = load_map(write_map(tmp_path, px, image="m.png"))
    assert grid.data[0].tolist() == [-1, 100, 0]


def test_rgb_pixels_use_channel_mean() -> None:
    rgb = np.array([[[255, 0, 0], [255, 255, 0]]], dtype=np.float64)  # shade 1/3, 2/3
    out = decode_pixels(rgb, None, "trinary", False, 0.65, 0.196)
    assert out[0].tolist() == [100, -1]


def test_raw_mode_keeps_values_and_ignores_negate(tmp_path: Path) -> None:
    px = np.array([[0, 42, 100, 101, 255]], dtype=np.uint8)
    for negate in (0, 1):
        grid = load_map(write_map(tmp_path, px, negate=negate, extra="mode: raw\n"))
        assert grid.data[0].tolist() == [0, 42, 100, -1, -1]
    # raw: a cell blocks when its percent is above occupied_thresh (65 → 66 and up).
    assert grid.occupied_threshold == 66


def test_unknown_blocks_unless_allowed(tmp_path: Path) -> None:
    grid = load_map(write_map(tmp_path, np.array([[205, 254, 0]], dtype=np.uint8)))
    assert grid.blocked().tolist() == [[True, False, True]]
    assert grid.blocked(allow_unknown=True).tolist() == [[False, False, True]]


def test_nonzero_origin_yaw_is_kept(tmp_path: Path) -> None:
    grid = load_map(write_map(tmp_path, PIXELS, origin="[0, 0, 0.5]"))
    assert grid.origin == (0.0, 0.0, 0.5)
    assert grid.source["origin"] == [0, 0, 0.5]


def test_image_path_is_relative_to_yaml_and_absolute_works(tmp_path: Path) -> None:
    sub = tmp_path / "imgs"
    sub.mkdir()
    Image.fromarray(PIXELS, mode="L").save(sub / "a.pgm", format="PPM")
    (tmp_path / "rel.yaml").write_text(
        "image: imgs/a.pgm\nresolution: 0.1\norigin: [0, 0, 0]\nnegate: 0\n"
        "occupied_thresh: 0.65\nfree_thresh: 0.196\n"
    )
    (tmp_path / "abs.yaml").write_text(
        f"image: {sub / 'a.pgm'}\nresolution: 0.1\norigin: [0, 0, 0]\nnegate: 0\n"
        "occupied_thresh: 0.65\nfree_thresh: 0.196\n"
    )
    assert np.array_equal(load_map(tmp_path / "rel.yaml").data, load_map(tmp_path / "abs.yaml").data)


def test_plain_ascii_pgm_is_read(tmp_path: Path) -> None:
    (tmp_path / "a.pgm").write_text("P2\n3 1\n255\n0 254 205\n")
    yaml_path = tmp_path / "a.yaml"
    yaml_path.write_text(
        "image: a.pgm\nresolution: 0.1\norigin: [0, 0, 0]\nnegate: 0\n"
        "occupied_thresh: 0.65\nfree_thresh: 0.196\n"
    )
    assert load_map(yaml_path).data[0].tolist() == [100, 0, -1]


# ---------------------------------------------------------------------------------------------- round trip


@pytest.mark.parametrize(
    ("mode", "occ", "free", "image"),
    [("trinary", 0.65, 0.196, "m.pgm"), ("trinary", 0.65, 0.25, "m.pgm"), ("scale", 0.8, 0.1, "m.png"),
     ("raw", 0.65, 0.196, "m.pgm")],
)
def test_round_trip(tmp_path: Path, mode: str, occ: float, free: float, image: str) -> None:
    rng = np.random.default_rng(7)
    if mode == "trinary":
        px = rng.choice(np.array([0, 254, 205, 120, 30], dtype=np.uint8), size=(17, 23))
        px_img = px
    elif mode == "scale":
        grey = rng.integers(0, 256, size=(17, 23), dtype=np.uint8)
        alpha = np.where(rng.random((17, 23)) < 0.1, 0, 255).astype(np.uint8)
        px_img = np.stack([grey, alpha], axis=2)
    else:
        px_img = rng.integers(0, 256, size=(17, 23), dtype=np.uint8)
    first = load_map(write_map(tmp_path, px_img, image=image, occ=occ, free=free, origin="[-3.5, 2.25, 0.1]",
                               resolution=0.05, extra=f"mode: {mode}\nmesh: cave.stl\n"))
    out = tmp_path / "out" / "saved.yaml"
    save_map(first, out)
    second = load_map(out)
    assert np.array_equal(first.data, second.data)
    assert second.origin == first.origin
    assert second.resolution_m == first.resolution_m
    assert second.source["mode"] == mode
    assert second.source["mesh"] == "cave.stl"
    assert second.occupied_threshold == first.occupied_threshold
    # Saving again gives byte-identical files.
    out2 = tmp_path / "out2" / "saved.yaml"
    save_map(second, out2)
    assert out.read_bytes() == out2.read_bytes()
    img_name = second.source["image"]
    assert (out.parent / img_name).read_bytes() == (out2.parent / img_name).read_bytes()


def test_save_fresh_grid_uses_nav2_pixels(tmp_path: Path) -> None:
    occupied = np.zeros((4, 5), dtype=bool)
    occupied[0, 0] = True
    grid = OccupancyGrid.from_occupied(occupied, 0.1, (2.0, 3.0, 0.0), name="fresh")
    data = grid.data.copy()
    data[3, 4] = -1
    grid = OccupancyGrid(data=data, resolution_m=0.1, origin=(2.0, 3.0, 0.0))
    path = save_map(grid, tmp_path / "fresh.yaml")
    with Image.open(tmp_path / "fresh.pgm") as img:
        px = np.asarray(img)
    assert px[3, 0] == 0  # bottom-left occupied cell is the last image row
    assert px[0, 4] == 205  # unknown
    assert px[1, 1] == 254
    assert np.array_equal(load_map(path).data, data)


# ---------------------------------------------------------------------------------------------- errors


def _error(path: Path) -> MapError:
    with pytest.raises(MapError) as info:
        load_map(path)
    return info.value


def test_missing_yaml(tmp_path: Path) -> None:
    err = _error(tmp_path / "nope.yaml")
    assert err.field == "map" and "does not exist" in err.msg


def test_malformed_yaml(tmp_path: Path) -> None:
    path = tmp_path / "bad.yaml"
    path.write_text("image: [unclosed\nresolution: 0.1\n")
    assert _error(path).field == "map"
    path.write_text("just a string\n")
    assert _error(path).field == "map"


@pytest.mark.parametrize("key", ["image", "resolution", "origin", "occupied_thresh", "free_thresh", "negate"])
def test_missing_required_key(tmp_path: Path, key: str) -> None:
    yaml_path = write_map(tmp_path, PIXELS)
    lines = [ln for ln in yaml_path.read_text().splitlines() if not ln.startswith(f"{key}:")]
    yaml_path.write_text("\n".join(lines) + "\n")
    err = _error(yaml_path)
    assert err.field == key and "missing" in err.msg


@pytest.mark.parametrize("resolution", ["0", "-0.05", "abc", ".nan", "true"])
def test_bad_resolution(tmp_path: Path, resolution: str) -> None:
    assert _error(write_map(tmp_path, PIXELS, resolution=resolution)).field == "resolution"


@pytest.mark.parametrize("origin", ["[0, 0]", "[0, 0, abc]", "5", "[0, .inf, 0]"])
def test_bad_origin(tmp_path: Path, origin: str) -> None:
    assert _error(write_map(tmp_path, PIXELS, origin=origin)).field == "origin"


def test_missing_image_file(tmp_path: Path) -> None:
    yaml_path = write_map(tmp_path, PIXELS)
    (tmp_path / "m.pgm").unlink()
    err = _error(yaml_path)
    assert err.field == "image" and "does not exist" in err.msg


def test_image_not_pgm_or_png(tmp_path: Path) -> None:
    yaml_path = write_map(tmp_path, PIXELS)
    Image.fromarray(PIXELS, mode="L").save(tmp_path / "m.bmp", format="BMP")
    (tmp_path / "t.txt").write_text("not an image")
    yaml_path.write_text(yaml_path.read_text().replace("m.pgm", "m.bmp"))
    assert _error(yaml_path).field == "image"
    yaml_path.write_text(yaml_path.read_text().replace("m.bmp", "t.txt"))
    assert _error(yaml_path).field == "image"
    # A colour PPM is not a PGM even though the same reader handles it.
    Image.fromarray(np.zeros((2, 2, 3), dtype=np.uint8), mode="RGB").save(tmp_path / "c.ppm", format="PPM")
    yaml_path.write_text(yaml_path.read_text().replace("t.txt", "c.ppm"))
    assert _error(yaml_path).field == "image"


@pytest.mark.parametrize(
    ("occ", "free", "field"),
    [(1.5, 0.2, "occupied_thresh"), (0.65, -0.1, "free_thresh"), (0.3, 0.5, "free_thresh"),
     ("x", 0.2, "occupied_thresh")],
)
def test_thresholds_out_of_range(tmp_path: Path, occ: object, free: object, field: str) -> None:
    assert _error(write_map(tmp_path, PIXELS, occ=occ, free=free)).field == field


def test_unknown_mode_and_bad_negate(tmp_path: Path) -> None:
    assert _error(write_map(tmp_path, PIXELS, extra="mode: fancy\n")).field == "mode"
    assert _error(write_map(tmp_path, PIXELS, negate=2)).field == "negate"


def test_map_files_prefers_the_grid_and_stays_in_the_folder(tmp_path):
    from planner.maps.catalogue import map_files

    for name in ("cave.stl", "cave.yaml", "maze.yml", ".hidden.yaml", "notes.txt"):
        (tmp_path / name).write_text("x")
    (tmp_path / "sub").mkdir()
    (tmp_path / "sub" / "inner.yaml").write_text("x")
    assert map_files(tmp_path) == {"cave": tmp_path / "cave.yaml", "maze": tmp_path / "maze.yml"}
    assert map_files(tmp_path / "missing") == {}
