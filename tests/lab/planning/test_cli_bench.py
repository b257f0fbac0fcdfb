"""``sphereplan bench``: a table, a CSV and a PNG; bad input exits 2."""

import csv

from service.cli import main


def test_bench_writes_table_csv_and_png(tmp_path, capsys):
    out_csv, out_png = tmp_path / "b.csv", tmp_path / "b.png"
    code = main(["bench", "--problems", "bench_over_wall1", "--runs", "1", "--ompl-time", "0.5", "--rrt-time", "0",
                 "--csv", str(out_csv), "--png", str(out_png), "-q"])
    assert code == 0
    table, err = capsys.readouterr()
    assert err == ""  # -q (here after the verb): no progress bar
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


def test_bench_figure_marks_failed_and_unsolvable_runs():
    """Issue #13: bench.png shows failed runs and unsolvable problems explicitly, with a title and the
    dashed 1.05 line and RRT*'s bar explained in the legend."""
    import math

    from lab.planning.shipped import BenchRow, bench_figure
    from planner.plotstyle import legend_labels

    def row(problem, planner, solvable, success, t, ratio, note=""):
        return BenchRow(problem, planner, solvable, success, t, t, 10.0 * ratio, ratio, 0.3, 0.9, 5, note)

    rows = [row("easy", "sphere-hybrid-a*", True, True, 0.01, 1.02),
            row("easy", "ompl-BIT*", True, True, 0.1, 1.0, "time = first solution"),
            row("easy", "ompl-RRT*", True, False, 2.0, math.nan, "no solution in time"),
            row("sealed", "sphere-hybrid-a*", False, True, 0.0003, math.nan, "208: no path"),
            row("sealed", "ompl-BIT*", False, True, 10.0, math.nan, "no solution in time"),
            row("sealed", "ompl-RRT*", False, True, 2.0, math.nan, "no solution in time")]
    fig = bench_figure(rows, "bench title", 3, {"ompl-BIT*": 10.0, "ompl-RRT*": 2.0})
    labels = legend_labels(fig)
    assert fig._suptitle.get_text() == "bench title"
    assert any("RRT*" in label and "not a first solution" in label for label in labels)
    assert any("5 %" in label for label in labels)  # the dashed 1.05 line
    assert any("failed on a solvable problem" in label for label in labels)
    ticks = [t.get_text() for t in fig.axes[1].get_xticklabels()]
    assert ticks == ["easy", "sealed (unsolvable)"]  # unsolvable problems included
    texts = [t.get_text() for t in fig.axes[1].texts]
    assert "timeout" in texts and "unsolvable (reported by Hybrid A*)" in texts
