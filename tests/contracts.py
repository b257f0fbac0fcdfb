"""Field sets of the JSON contracts (docs/contracts.md), written once for every test that checks them."""

SIM_METRIC_KEYS = frozenset({
    "cross_track_rms_m", "cross_track_max_m", "final_position_error_m", "final_yaw_error_rad",
    "min_clearance_m", "collided", "duration_s", "fallback_steps", "mpc_solve_ms_p50", "mpc_solve_ms_p95",
})
