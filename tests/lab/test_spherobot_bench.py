"""The reconfiguration plan-time bench (``sphereplan bench --suite reconfigure``)."""

from __future__ import annotations

from lab.spherobot_bench import benchmark, format_benchmark


def test_benchmark_table():
    rows = benchmark(n=3, seed=1)
    assert {(r["method"], r["mode"]) for r in rows} == {
        (m, k) for m in ("arc", "triangle") for k in ("partial", "complete")
    }
    text = format_benchmark(rows)
    assert "plan med ms" in text and len(text.splitlines()) == 6
