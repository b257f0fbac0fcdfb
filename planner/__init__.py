"""sphereplan's algorithms: maps, robot profiles, collision checking and the spherical Hybrid A*.

Nothing here imports a transport (HTTP, Zenoh) or a wire model; ``service`` depends on ``planner``,
never the other way round.
"""
