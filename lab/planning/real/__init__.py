"""The real-map benchmark: seeded random problems on Nav2's maps, sphereplan against OMPL BIT* as reference.

``sphereplan bench --suite real`` runs this package (docs/planning.md, "The real-map benchmark"). Problems are
drawn the way Nav2's planner benchmark (``tools/planner_benchmarking/metrics.py``) draws them, with the
robot's real footprint: a uniformly random cell away from the map's border and a uniformly random yaw for the
start, then the same for the goal at least a minimum distance away; a draw is kept only when the padded
footprint polygon (:attr:`~planner.robot.RobotProfile.footprint_polygon`) is free there by the exact check of
:mod:`lab.planning.referee`. Every problem also gets a proof of unreachability where one is
cheap: start and goal in different connected parts of the space the footprint's inscribed disc can reach.

Each problem is given to sphereplan (:func:`planner.hybrid_astar.plan.plan_path`, default options unless told
otherwise) and to OMPL's BIT* on a Dubins and a Reeds–Shepp state space at the robot's minimum turning radius
with the exact polygon validity check, each with the same time limit. BIT* is the solvability and length
reference: its first-solution time is the time to beat, its length after the full time limit the length to
match. Every path (sphereplan's and BIT*'s) is re-checked with the exact polygon on states at most half a
cell apart, and its true footprint clearance is measured with the same polygon.
"""
