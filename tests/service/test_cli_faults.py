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


def zenoh_config_not_json(folder: Path) -> str:
    (folder / "passwd.json5").write_text("root:x:0:0:root:/root:/bin/bash\n")
    return str(folder / "passwd.json5")


# issue 25, findings 4, 5, 7, 9: every verb, checked before anything starts (no worker is warmed)
VERB_CASES = [
    ("huge integer in a float option", ["plan", "--map", GARAGE, *POSES, "--options", '{"greed": 1' + "0" * 400 + "}"],
     "options.greed"),
    ("reconfigure with an absurd radius", ["reconfigure", "--start", "0", "0", "--goal", "1", "1", "--radius", "1e308"],
     "radius"),
    ("reconfigure farther than 200 radii", ["reconfigure", "--start", "0", "0", "--goal", "1e6", "1", "--radius",
                                            "1e-6"], "goal"),
    ("a gait of 1e12 m", ["tensegrity", "gait", "--distance", "1e12", "--out", "/tmp/never-written.json"], "distance"),
    ("--zenoh-config not a Zenoh file", ["serve", "--port", "1", "--zenoh-config", "/etc/passwd"], "--zenoh-config"),
    ("--zenoh-config not JSON5", ["serve", "--port", "1", "--zenoh-config", "NOT_JSON5"], "--zenoh-config"),
    ("Zenoh beyond loopback without credentials", ["serve", "--port", "1", "--zenoh-listen", "tcp/0.0.0.0:7447"],
     "--zenoh-listen"),
    ("Zenoh on every interface without credentials", ["serve", "--port", "1", "--zenoh-config", "ALL_INTERFACES"],
     "--zenoh-config"),
    ("a robot pattern that is not one key chunk", ["serve", "--port", "1", "--robots", "a/**"], "zenoh_robots"),
]


@pytest.mark.parametrize(("case", "argv", "field"), VERB_CASES, ids=[c[0] for c in VERB_CASES])
def test_other_verbs_refuse_with_one_line(capsys: pytest.CaptureFixture[str], tmp_path: Path, case: str,
                                          argv: list[str], field: str) -> None:
    every = tmp_path / "every.json5"
    every.write_text('{mode: "peer"}')  # no listen endpoints: a peer listens on every interface
    argv = [zenoh_config_not_json(tmp_path) if a == "NOT_JSON5" else str(every) if a == "ALL_INTERFACES" else a
            for a in argv]
    code = main(argv)
    err = capsys.readouterr().err
    assert code == 2, err
    errors = [line for line in err.strip().splitlines() if ": error:" in line]
    assert "Traceback" not in err and len(errors) == 1 and field in errors[0], err
    assert "Uvicorn running" not in err and not Path("/tmp/never-written.json").exists()


def test_zenoh_beyond_loopback_is_allowed_with_credentials_or_insecure(tmp_path: Path) -> None:
    from service.cli import build_parser
    from service.cli.serve import settings_from_args

    token = tmp_path / "token"
    token.write_text("a-token-of-at-least-16-chars\n")
    for extra in (["--token-file", str(token)], ["--insecure"]):
        args = build_parser().parse_args(["serve", "--zenoh-listen", "tcp/0.0.0.0:7447", *extra])
        assert settings_from_args(args).zenoh_listen == "tcp/0.0.0.0:7447"
    args = build_parser().parse_args(["serve", "--robots", "r1, east-$*"])
    assert settings_from_args(args).zenoh_robots == ("r1", "east-$*")
