"""The perception timing bench (``sphereplan bench --suite perception``), on small frames: its rows and table."""

from __future__ import annotations

from lab.perception_bench import RESOLUTIONS, bench_perception, format_perception_bench
from service.cli import main


def test_rows_and_table() -> None:
    rows = bench_perception(runs=2, resolutions=((270, 206, 0.1),))
    (row,) = rows
    assert row["width"] == 270 and row["runs"] == 2 and row["threads"] == 1
    assert 0 < row["sgbm_median_s"] <= row["median_s"] <= row["max_s"] and row["cpu_median_s"] > 0
    assert row["num_disparities"] % 16 == 0 and row["kept"] > 0 and row["eis_median_s"] > 0
    assert row["box_points"] > 0 and row["box_error"] < 0.05
    table = format_perception_bench(rows)
    assert "paper s" in table and "CPU s" in table and "270 × 206" in table and "0.1" in table


def test_the_papers_three_resolutions() -> None:
    assert RESOLUTIONS == ((1624, 1240, 2.0), (812, 620, 0.3), (541, 413, 0.1))


def test_cli_suite(capsys) -> None:
    assert main(["bench", "--suite", "perception", "--runs", "1", "--resolutions", "200x150"]) == 0
    out = capsys.readouterr().out
    assert "200 × 150" in out and "—" in out  # no paper figure at a size the paper did not run
    assert main(["bench", "--suite", "perception", "--resolutions", "20x10"]) == 2
    assert "--resolutions" in capsys.readouterr().err
