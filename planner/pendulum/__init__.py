"""The pendulum sphere's own motion control (paper 001 §5, see docs/references.md and docs/pendulum.md).

The Euler–Lagrange model of eq. 16–19 as a simulation plant (:mod:`.dynamics`), the offset-free LMPC
speed controller of eq. 20–25 (:mod:`.lmpc`), the improved robust-servo LQR direction controller of
eq. 26–32 (:mod:`.rslqr`), PID baselines (:mod:`.pid`), the inner loop that couples them to the plant
(:mod:`.sphere`) and the experiments of Figs. 11–13 (:mod:`.experiments`, :mod:`.plot`).
"""
