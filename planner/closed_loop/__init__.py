"""Rolling a plan in closed loop (paper 001 §3 and §4.2, see docs/references.md).

The eq. 1 simulator with roll lag and disturbances, wheel odometry fused with GNSS in a Kalman filter
(eq. 2–3), the instruction-planning MPC tracker of eq. 15 (CasADi SQP), synthetic reference plans and
the ``simulate_plan`` entry point with its plot.
"""
