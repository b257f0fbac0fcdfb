"""The MPC step-time bench (``sphereplan bench --suite mpc``)."""

from __future__ import annotations

from lab.mpc_bench import bench_mpc, format_mpc_bench


def test_bench_rows() -> None:
    rows = bench_mpc(horizons=(8,), steps=20)
    assert len(rows) == 1 and rows[0]["horizon"] == 8 and rows[0]["steps"] >= 20
    assert 0 < rows[0]["p50_ms"] <= rows[0]["p95_ms"]
    assert "p50 ms" in format_mpc_bench(rows)
