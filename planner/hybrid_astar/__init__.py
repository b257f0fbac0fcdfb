"""Hybrid A* for roll-steered spheres (paper 001 §4.1, see docs/references.md).

The search expands children by the sphere kinematics of eq. 1 (with the corrections of eq. 14 derived
from it), checks them against the map's clearance model, and scores them with g from eq. 14f–h and
h = max(holonomic Dijkstra with obstacles, Dubins/Reeds–Shepp without). ``plan_path`` is the one-call API.
"""
