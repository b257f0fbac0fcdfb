"""The CLI never shows a traceback for what a user can type or point it at (issue 12, row 9): each case
exits 2 with one line naming the field."""

from pathlib import Path

import pytest

from planner.maps.catalogue import default_maps_dir
from service.cli import main

pytestmark = pytest.mark.faults

GARAGE = str(default_maps_dir() / "garage.yaml")
POSES = ["--start", "3.5", "8.05", "0", "--goal", "12", "8.05", "0"]


def huge_pgm_map(folder: Path) -> str:
    (folder / "huge.pgm").write_bytes(b"P5\n100000 100000\n255\n")
    (folder / "huge.yaml").write_text("image: huge.pgm\nresolution: 0.1\norigin: [0, 0, 0]\n"
                                      "occupied_thresh: 0.65\nfree_thresh: 0.2\nnegate: 0\n")
    return str(folder / "huge.yaml")


CASES = [
    ("huge start", ["--map", GARAGE, "--start", "1e308", "8", "0", "--goal", "12", "8.05", "0"], "start"),
    ("tiny state spacing", ["--map", GARAGE, *POSES, "--options", '{"state_spacing_m": 1e-300}'],
     "options.state_spacing_m"),
    ("huge PGM header", ["--map", "HUGE", *POSES], "--map"),
    ("--out a folder", ["--map", GARAGE, *POSES, "--out", "/tmp"], "--out"),
    ("--out nowhere", ["--map", GARAGE, *POSES, "--out", "/proc/nope/x.json"], "--out"),
    ("--plot nowhere", ["--map", GARAGE, *POSES, "--plot", "/proc/nope/x.png"], "--plot"),
    ("--plot unknown format", ["--map", GARAGE, *POSES, "--plot", "x.xyz"], "--plot"),
    ("deeply nested options", ["--map", GARAGE, *POSES, "--options", "[" * 100_000], "--options"),
]


@pytest.mark.parametrize(("case", "argv", "field"), CASES, ids=[c[0] for c in CASES])
def test_user_input_never_tracebacks(capsys: pytest.CaptureFixture[str], tmp_path: Path, case: str,
                                     argv: list[str], field: str) -> None:
    argv = [huge_pgm_map(tmp_path) if a == "HUGE" else a for a in argv]
    code = main(["plan", *argv])
    err = capsys.readouterr().err
    assert code == 2, err
    errors = [line for line in err.strip().splitlines() if ": error:" in line]  # progress lines may precede it
    assert "Traceback" not in err and len(errors) == 1 and field in errors[0], err
    assert not Path("x.xyz").exists()
