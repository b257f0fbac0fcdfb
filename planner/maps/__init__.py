"""Maps: the ROS map_server codec, the maps-folder catalogue and problem sets, mesh worlds, and the one
clearance model (a distance transform plus footprint queries) that every wing asks whether a pose is free.
"""
