"""The Nav2 maps shipped in maps/real/ load to exactly the grids of the original YAML + PGM files.

The originals are not in the repository, so the numbers below were recorded from them (nav2 rules,
``planner.maps.nav2.load_map`` on Nav2's own YAML + PGM): size, resolution, origin, the count of free,
occupied and unknown cells and a SHA-256 of the decoded grid. A lossy conversion, a changed threshold or
a flipped image changes at least one of them.
"""

from __future__ import annotations

import hashlib
from pathlib import Path

import numpy as np
import pytest
import yaml

from planner.maps.catalogue import list_maps, map_files
from planner.maps.nav2 import load_map
from service.cli import main

REAL = Path(__file__).resolve().parents[3] / "maps" / "real"
# name: (width, height, resolution, origin, free, occupied, unknown, sha256 of grid.data)
#: the synthetic Nav2-style maps tools/generate_real_maps.py builds (maps/real/README.md)
GENERATED = {"pockets", "bays"}
ORIGINALS = {
    "100by100_20": (2000, 2000, 0.05, (0.0, 0.0, 0.0), 3175585, 824415, 0,
                    "ab9b8f6a8c100953b7062ab64bceb6ce020dc007afd81dc699394c1461219b00"),
    "depot": (604, 307, 0.05, (0.0, 0.0, 0.0), 179481, 5947, 0,
              "04f0a508f25ad57d1569a63b02ae7ce4218c482f604541fe4ab6b7d911eb158c"),
    "smoothers_world": (300, 300, 0.05, (0.0, 0.0, 0.0), 79424, 10576, 0,
                        "f5ab76ab9fd58708a41536709d38ec49367791c4c1d577df807aa4d68953d09b"),
    "warehouse": (1006, 1674, 0.03, (-15.1, -25.0, 0.0), 1422292, 30951, 230801,
                  "cacdc3916c0b575ce45af6b6d5f907a7fa87017a904f93fdf51c11b129bbb4c9"),
}
# The YAML fields Nav2 ships, except ``image`` (now the PNG).
NAV2_FIELDS = {
    "100by100_20": {"resolution": 0.05, "origin": [0.0, 0.0, 0.0], "negate": 1, "occupied_thresh": 0.65,
                    "free_thresh": 0.196},
    "depot": {"mode": "trinary", "resolution": 0.05, "origin": [0.0, 0.0, 0], "negate": 0,
              "occupied_thresh": 0.65, "free_thresh": 0.25},
    "smoothers_world": {"resolution": 0.05, "origin": [0.0, 0.0, 0.0], "negate": 0, "occupied_thresh": 0.65,
                        "free_thresh": 0.196},
    "warehouse": {"mode": "trinary", "resolution": 0.03, "origin": [-15.1, -25, 0], "negate": 0,
                  "occupied_thresh": 0.65, "free_thresh": 0.1},
}


@pytest.mark.parametrize("name", sorted(ORIGINALS))
def test_shipped_real_map_is_the_original_grid(name: str) -> None:
    width, height, res, origin, free, occupied, unknown, digest = ORIGINALS[name]
    grid = load_map(REAL / f"{name}.yaml")
    assert (grid.width, grid.height, grid.resolution_m, grid.origin) == (width, height, res, origin)
    counts = [int(np.count_nonzero(grid.data == v)) for v in (0, 100, -1)]
    assert counts == [free, occupied, unknown]
    assert hashlib.sha256(grid.data.tobytes()).hexdigest() == digest


@pytest.mark.parametrize("name", sorted(NAV2_FIELDS))
def test_yaml_keeps_every_nav2_field(name: str) -> None:
    doc = yaml.safe_load((REAL / f"{name}.yaml").read_text())
    assert doc.pop("image") == f"{name}.png"
    assert doc == NAV2_FIELDS[name]
    assert (REAL / f"{name}.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_attribution_names_every_map() -> None:
    readme = (REAL / "README.md").read_text()
    notice = (REAL.parents[1] / "NOTICE").read_text()
    assert "Apache" in readme and "ros-navigation/navigation2" in readme
    assert "ros-navigation/navigation2" in notice and "maps/real" in notice
    for name in ORIGINALS:
        assert f"{name}.yaml" in readme and f"{name}." in notice


def test_flat_index_skips_the_real_subfolder_but_lists_it_on_request(capsys: pytest.CaptureFixture[str]) -> None:
    """Deliberate: ``sphereplan maps`` and name lookup see only maps/ itself; maps/real is listed by path."""
    assert not set(ORIGINALS) & set(map_files(REAL.parent))
    assert main(["maps"]) == 0
    assert "100by100_20" not in capsys.readouterr().out
    listed = {m["name"]: m for m in list_maps(REAL)}
    assert set(listed) == set(ORIGINALS) | GENERATED
    assert listed["100by100_20"]["size_m"] == [100.0, 100.0]
    assert all("error" not in m for m in listed.values())


def test_the_generated_maps_are_what_their_generator_makes(tmp_path: Path) -> None:
    """pockets and bays are rebuilt byte for byte by tools/generate_real_maps.py (maps/real/README.md says so)."""
    import subprocess
    import sys

    repo = REAL.parents[1]
    proc = subprocess.run([sys.executable, str(repo / "tools" / "generate_real_maps.py"), "--out", str(tmp_path)],
                          capture_output=True, text=True, cwd=repo)
    assert proc.returncode == 0, proc.stderr
    for name in GENERATED:
        made = load_map(tmp_path / f"{name}.yaml")
        shipped = load_map(REAL / f"{name}.yaml")
        assert made.data.shape == shipped.data.shape and (made.data == shipped.data).all(), name
