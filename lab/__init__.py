"""The lab: benchmarks, independent referees, experiments, tuning, load tests and figure makers.

It imports the product (:mod:`planner`, :mod:`service`) and is never imported by it, except lazily by the CLI
verbs that run it (``sphereplan bench`` and ``sphereplan controllers tune|figures|bench``); a test walks every
import of ``planner/`` and ``service/`` to hold that line. Nav2 keeps its benchmark in
``tools/planner_benchmarking/`` and OMPL in ``ompl/tools/benchmark/`` for the same reason.

* :mod:`lab.planning` — the shipped-set benchmark (:mod:`.shipped`), the real-map benchmark (:mod:`.real`) and
  the benchmark's independent footprint referee (:mod:`.referee`);
* :mod:`lab.pendulum` — paper 001's controller figures, tuning and timing, the minimum-rise bound, the
  dynamic-plant rollout of every shipped problem;
* :mod:`lab.spherobot_bench`, :mod:`lab.mpc_bench` — reconfiguration plan times and MPC step times;
* :mod:`lab.loadtest` — the service's load test; :mod:`lab.vpip_mujoco_figures` — DAEDALUS's MuJoCo figures.
"""
