"""``sphereplan bench``: a table, a CSV and a PNG; bad input exits 2."""

import csv

from service.cli import main


def test_bench_writes_table_csv_and_png(tmp_path, capsys):
    out_csv, out_png = tmp_path / "b.csv", tmp_path / "b.png"
    code = main(["bench", "--problems", "bench_over_wall1", "--runs", "1", "--ompl-time", "0.5", "--rrt-time", "0",
                 "--csv", str(out_csv), "--png", str(out_png)])
    assert code == 0
    table = capsys.readouterr().out
    assert "sphere-hybrid-a*" in table and "ompl-BIT*" in table
    rows = list(csv.DictReader(out_csv.open()))
    assert {r["planner"] for r in rows} == {"sphere-hybrid-a*", "ompl-BIT*"}
    ours = next(r for r in rows if r["planner"] == "sphere-hybrid-a*")
    assert ours["success"] == "True" and float(ours["length_m"]) > 0
    assert out_png.stat().st_size > 5000


def test_bench_bad_input(capsys):
    assert main(["bench", "--runs", "0"]) == 2
    assert main(["bench", "--problems", "no-such-problem", "--ompl-time", "0", "--rrt-time", "0"]) == 2
    assert "--problems" in capsys.readouterr().err
