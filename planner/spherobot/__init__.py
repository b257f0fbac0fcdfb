"""Spherobot reconfiguration (paper 004, see docs/references.md).

Bring a rolling sphere to rest at a goal position with its camera point P on top and a chosen heading:
spherical-triangle manoeuvres (§3) and straight-roll + circle manoeuvres (§4), every plan proved by exact
SO(3) rolling without slipping and, on a map, by sweeping the sphere's disc over the grid.
"""
